"""The shared core: robot models and what every method family needs of them.

- :mod:`~capmap.core.robot`       robot description (SI) -> Pinocchio model
- :mod:`~capmap.core.reduction`   lock a joint (or none) -> the arm that still moves
- :mod:`~capmap.core.kinematics`  batched serial-chain FK and Jacobians, pose errors
- :mod:`~capmap.core.ik`          every inverse-kinematics branch of a 6-joint arm
- :mod:`~capmap.core.configuration` configuration labels of IK solutions (shoulder / elbow / wrist, or aspects)
- :mod:`~capmap.core.dynamics`    joint torques and base wrench (Pinocchio RNEA), payload models
- :mod:`~capmap.core.coefficients` the exact capacity coefficients c0, L, Q, S (one type, batched or not)
- :mod:`~capmap.core.tracking`    one IK branch followed continuously along a path
- :mod:`~capmap.core.profiles`    trapezoid and jerk-limited S-curve timing of straight segments
- :mod:`~capmap.core.limits`      limits |y0 + x s| <= L on outputs affine in a scalar
- :mod:`~capmap.core.parallel`    a row-wise batch split over forked processes (a job's threads)

Nothing here reads files, config keys or plots; everything is SI with radians.
"""

from capmap._lazy import lazy_exports

_EXPORTS = {
    'coefficients': 'coefficients',
    'configuration': 'configuration',
    'configurations_of': 'configuration',
    'dynamics': 'dynamics',
    'ik': 'ik',
    'kinematics': 'kinematics',
    'limits': 'limits',
    'parallel': 'parallel',
    'profiles': 'profiles',
    'reduction': 'reduction',
    'robot': 'robot',
    'tracking': 'tracking',
    'ArmDynamics': 'dynamics',
    'output_names': 'dynamics',
    'payload_models': 'dynamics',
    'AffineLimits': 'limits',
    'LockedArm': 'reduction',
    'free': 'reduction',
    'lock': 'reduction',
    'Robot': 'robot',
    'RobotDescription': 'robot',
    'build_robot': 'robot',
}

__all__ = [
    "AffineLimits",
    "ArmDynamics",
    "LockedArm",
    "Robot",
    "RobotDescription",
    "build_robot",
    "coefficients",
    "configuration",
    "configurations_of",
    "dynamics",
    "free",
    "ik",
    "kinematics",
    "limits",
    "lock",
    "output_names",
    "parallel",
    "payload_models",
    "profiles",
    "reduction",
    "robot",
    "tracking",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
