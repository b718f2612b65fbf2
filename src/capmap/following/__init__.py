"""Method family 2: torque-limited following of a fixed Cartesian path, compared with TOPP-RA.

- :mod:`~capmap.following.path`             a straight segment as a joint path (exact IK, q', q'')
- :mod:`~capmap.following.path_dynamics`    tau = a sdd + b sd^2 + c along it; the speed ceiling
- :mod:`~capmap.following.follower`         the online follower (one control period at a time)
- :mod:`~capmap.following.toppra_reference` TOPP-RA on the same path and limits
- :mod:`~capmap.following.comparison`       the follower against the command and TOPP-RA
"""

from capmap.following import comparison, follower, path, path_dynamics, toppra_reference
from capmap.following.comparison import FollowComparison, compare
from capmap.following.follower import FollowSettings, follow, follow_segment
from capmap.following.toppra_reference import time_optimal

__all__ = ["path", "path_dynamics", "follower", "toppra_reference", "comparison", "FollowSettings", "follow",
           "follow_segment", "time_optimal", "FollowComparison", "compare"]
