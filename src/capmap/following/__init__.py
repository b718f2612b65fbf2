"""Method family 2: torque-limited following of a fixed Cartesian path, compared with TOPP-RA.

- :mod:`~capmap.following.path`             a straight segment as a joint path (exact IK, q', q'')
- :mod:`~capmap.following.path_dynamics`    tau = a sdd + b sd^2 + c along it; the speed ceiling
- :mod:`~capmap.following.follower`         the online follower (one control period at a time)
- :mod:`~capmap.following.toppra_reference` TOPP-RA on the same path and limits
- :mod:`~capmap.following.comparison`       the follower against the command and TOPP-RA
"""

from capmap._lazy import lazy_exports

_EXPORTS = {
    'comparison': 'comparison',
    'follower': 'follower',
    'path': 'path',
    'path_dynamics': 'path_dynamics',
    'toppra_reference': 'toppra_reference',
    'FollowComparison': 'comparison',
    'compare': 'comparison',
    'FollowSettings': 'follower',
    'follow': 'follower',
    'follow_segment': 'follower',
    'ToppraSettings': 'toppra_reference',
    'time_optimal': 'toppra_reference',
}

__all__ = [
    "FollowComparison",
    "FollowSettings",
    "ToppraSettings",
    "compare",
    "comparison",
    "follow",
    "follow_segment",
    "follower",
    "path",
    "path_dynamics",
    "time_optimal",
    "toppra_reference",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
