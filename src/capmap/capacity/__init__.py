"""Method family 1, the capacity map: what a locked arm can carry, and where; planning and verification.

- :mod:`~capmap.capacity.directions`   motion-direction sets (the paper's grid, near-uniform sphere)
- :mod:`~capmap.capacity.sampling`     Monte Carlo workspace (joint samples, voxel fill)
- :mod:`~capmap.capacity.engine`       exact dynamic load-carrying capacity of configurations and points
- :mod:`~capmap.capacity.voxels`       the voxel grid and per-voxel minima
- :mod:`~capmap.capacity.planning`     improved A* through the voxels that carry the payload
- :mod:`~capmap.capacity.verification` the real motion along a path: loads, segment capacities, verdicts
"""

from capmap.capacity import directions, engine, planning, sampling, verification, voxels
from capmap.capacity.engine import LoadLimits, Motion, point_capacity
from capmap.capacity.planning import plan
from capmap.capacity.verification import judge, verify_path
from capmap.capacity.voxels import Grid, voxelise

__all__ = ["directions", "sampling", "engine", "voxels", "planning", "verification", "LoadLimits", "Motion",
           "point_capacity", "Grid", "voxelise", "plan", "verify_path", "judge"]
