"""capmap: what a manipulator with a locked joint can still carry, and where.

Stage modules (numerics are pure functions on arrays, batch on the leading axis):

- :mod:`capmap.robot`      robot description (DH YAML or URDF) -> Pinocchio model
- :mod:`capmap.locking`    lock one joint at an angle -> the reduced arm
- :mod:`capmap.kinematics` serial-chain forward kinematics and Jacobians (batched numpy)
- :mod:`capmap.ik`         all inverse-kinematics branches of the locked arm
- :mod:`capmap.directions` motion-direction sets (paper grid, near-uniform sphere)
- :mod:`capmap.dynamics`   constrained quantities (joint torques, base wrench) via Pinocchio
- :mod:`capmap.capacity`   exact dynamic load-carrying capacity
"""

__version__ = "0.1.0"
