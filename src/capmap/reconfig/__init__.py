"""Method family 3: a reconfigurable space robot. Two arms capture each other; one passive
cylindrical joint is unlocked and its boom reconfigured while the closed chain's long side
avoids singularities in its null space.

- :mod:`~capmap.reconfig.multiarm`    a platform of arms with revolute and passive cylindrical joints
- :mod:`~capmap.reconfig.loop`        the closed chain cut at the unlocked joint into two open chains
- :mod:`~capmap.reconfig.law`         the quintic motion law of (theta, d)
- :mod:`~capmap.reconfig.redundancy`  J^+, manipulability m and its exact gradient, null space
- :mod:`~capmap.reconfig.planner`     null-space (and pseudo-inverse) integration under rate and range limits
- :mod:`~capmap.reconfig.problem`     a problem put together; the robot's state and loop closure along a run
"""

from capmap._lazy import lazy_exports

_EXPORTS = {
    'law': 'law',
    'loop': 'loop',
    'multiarm': 'multiarm',
    'planner': 'planner',
    'problem': 'problem',
    'redundancy': 'redundancy',
    'QuinticLaw': 'law',
    'LoopSplit': 'loop',
    'close_capture': 'loop',
    'split_loop': 'loop',
    'PlannerSettings': 'planner',
    'Reconfiguration': 'planner',
    'reconfigure': 'planner',
    'ReconfigProblem': 'problem',
    'build_problem': 'problem',
    'closure_errors': 'problem',
    'PlatformDescription': 'multiarm',
    'PlatformState': 'multiarm',
    'platform_model': 'multiarm',
}

__all__ = [
    "LoopSplit",
    "PlannerSettings",
    "PlatformDescription",
    "PlatformState",
    "QuinticLaw",
    "ReconfigProblem",
    "Reconfiguration",
    "build_problem",
    "close_capture",
    "closure_errors",
    "law",
    "loop",
    "multiarm",
    "planner",
    "platform_model",
    "problem",
    "reconfigure",
    "redundancy",
    "split_loop",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
