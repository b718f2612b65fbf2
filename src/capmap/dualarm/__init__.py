"""Method family 4: dual 7-DOF arms in a confined space. A safety envelope fitted to a point cloud,
analytic swept-sphere distances, and augmented-Lagrangian DDP (Crocoddyl's FDDP, compiled) of a satellite
panel assembly. Three sub-packages, one per concept, and the family's tables:

- :mod:`~capmap.dualarm.geometry`  primitives and their distances: capsules and swept triangles
  (``primitives``), batched closest points (``distance``, compiled), primitives on joints with pairs, safety
  distances and q-gradients (``collision``), pair groups culled by one test (``broadphase``), which pairs are
  near (``proximity``), the revolute chain packed for compiled kinematics and distances (``chain``)
- :mod:`~capmap.dualarm.scene`     what the arms move in and with: the scene's solids, the panel and a
  synthetic scan (``solids``), envelopes fitted to a cloud (``cloud``), the space no camera observed
  (``unknown``, and the motion against it: ``unobserved``), the two-arm robot and its capsules (``robot``)
- :mod:`~capmap.dualarm.ocp`       the optimal-control problem and its solver: the task's constraints
  (``task``), the problem put together (``assembly``), the node models (``crocoddyl_nodes``: Crocoddyl's on
  Pinocchio, the reference; ``node_kernel`` and ``compiled_nodes``: compiled, the default; ``lie``: their
  SO(3)/SE(3) logarithms), FDDP compiled (``fddp``), the augmented-Lagrangian loop (``solver``, ``settings``),
  a solution's errors and safety (``evaluate``), the motion and its tables (``motion``), the held panel's
  torques (``torques``)
- :mod:`~capmap.dualarm.tables`    the collision-model tables (column schemas) and their readers
- :mod:`~capmap.dualarm.job`       what a job plans with (its inputs, horizon and planning settings), and
  :mod:`~capmap.dualarm.plan` its motion planned around the unknown space
- :mod:`~capmap.dualarm.build`     the config's sections into the family's settings and robots; the family's
  file loaders: ``scene_file`` (scene YAML), ``cloud_file`` (a user's point cloud)
"""

__all__ = ["geometry", "scene", "ocp", "tables"]
