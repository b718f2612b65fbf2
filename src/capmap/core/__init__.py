"""The shared core: robot models and what every method family needs of them.

- :mod:`~capmap.core.robot`       robot description (SI) -> Pinocchio model
- :mod:`~capmap.core.reduction`   lock a joint (or none) -> the arm that still moves
- :mod:`~capmap.core.kinematics`  batched serial-chain FK and Jacobians, pose errors
- :mod:`~capmap.core.ik`          every inverse-kinematics branch of a 6-joint arm
- :mod:`~capmap.core.dynamics`    joint torques and base wrench (Pinocchio RNEA), payload models
- :mod:`~capmap.core.tracking`    one IK branch followed continuously along a path
- :mod:`~capmap.core.profiles`    trapezoid and jerk-limited S-curve timing of straight segments
- :mod:`~capmap.core.limits`      limits |y0 + x s| <= L on outputs affine in a scalar

Nothing here reads files, config keys or plots; everything is SI with radians.
"""

from capmap.core import dynamics, ik, kinematics, limits, profiles, reduction, robot, tracking
from capmap.core.dynamics import ArmDynamics, output_names, payload_models
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm, free, lock
from capmap.core.robot import Robot, RobotDescription, build_robot

__all__ = ["robot", "reduction", "kinematics", "ik", "dynamics", "tracking", "profiles", "limits",
           "Robot", "RobotDescription", "build_robot", "LockedArm", "lock", "free", "ArmDynamics", "output_names",
           "payload_models", "AffineLimits"]
