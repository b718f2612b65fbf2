"""Method family 4: dual 7-DOF arms in a confined space. A safety envelope fitted to a point cloud,
analytic swept-sphere distances, and augmented-Lagrangian DDP (Crocoddyl's FDDP, compiled) of a satellite
panel assembly.

- :mod:`~capmap.dualarm.scene`       the scene's solids, the panel and its poses; a synthetic scan
- :mod:`~capmap.dualarm.cloud`       swept triangles and capsules fitted to a cloud (coverage checked)
- :mod:`~capmap.dualarm.primitives`  capsules, swept triangles, the minimum-volume capsule
- :mod:`~capmap.dualarm.distance`    batched segment-segment and segment-triangle closest points (compiled)
- :mod:`~capmap.dualarm.robot`       the two-arm robot (reduced Pinocchio model) and its capsules
- :mod:`~capmap.dualarm.collision`   primitives on joints, pairs, safety distances and q-gradients
- :mod:`~capmap.dualarm.task`        the task's equality constraints at a node
- :mod:`~capmap.dualarm.assembly`    the problem put together; warm start; clearance of key poses
- :mod:`~capmap.dualarm.settings`    cost weights and the AL loop's parameters
- :mod:`~capmap.dualarm.ocp`         one Crocoddyl action model per node (AL terms or constraints), on Pinocchio
- :mod:`~capmap.dualarm.lie`         SO(3)/SE(3) logarithms and their Jacobians, compiled
- :mod:`~capmap.dualarm.chain`       the revolute chain packed for compiled kinematics and distances
- :mod:`~capmap.dualarm.broadphase`  pair groups: a moving primitive against a static body, culled by one test
- :mod:`~capmap.dualarm.proximity`   which pairs are near: batched pair distances with culling
- :mod:`~capmap.dualarm.node_kernel` the compiled node: cost, constraints and derivatives in one function
- :mod:`~capmap.dualarm.nodes`       the node model compiled: one numba call per calc / calcDiff (the default)
- :mod:`~capmap.dualarm.fddp`        Crocoddyl's FDDP compiled, with the node kernel inside (the default inner solve)
- :mod:`~capmap.dualarm.solver`      the augmented-Lagrangian loop around FDDP
- :mod:`~capmap.dualarm.evaluate`    errors and safety of a solution, on the nodes and a finer grid
"""

__all__ = [
           "assembly",
           "broadphase",
           "chain",
           "cloud",
           "collision",
           "distance",
           "evaluate",
           "fddp",
           "lie",
           "node_kernel",
           "nodes",
           "ocp",
           "primitives",
           "proximity",
           "robot",
           "scene",
           "settings",
           "solver",
           "task",
]
