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

from capmap.reconfig import law, loop, multiarm, planner, problem, redundancy
from capmap.reconfig.law import QuinticLaw
from capmap.reconfig.loop import LoopSplit, close_capture, split_loop
from capmap.reconfig.planner import PlannerSettings, Reconfiguration, reconfigure
from capmap.reconfig.problem import ReconfigProblem, build_problem, closure_errors
from capmap.reconfig.multiarm import PlatformDescription, PlatformState, platform_model

__all__ = ["multiarm", "loop", "law", "redundancy", "planner", "problem", "ReconfigProblem", "build_problem",
           "closure_errors", "PlatformDescription", "PlatformState",
           "platform_model", "LoopSplit", "split_loop", "close_capture", "QuinticLaw", "PlannerSettings",
           "Reconfiguration", "reconfigure"]
