"""Method family 1, the capacity map: what a locked arm can carry, and where; planning and verification.

- :mod:`~capmap.capacity.directions`   motion-direction sets (the whole sphere, the paper's grid, near-uniform sphere)
- :mod:`~capmap.capacity.sphere`       the exact minimum over the sphere of motion directions (compiled)
- :mod:`~capmap.capacity.sweep`        the minimum over a direction set (compiled)
- :mod:`~capmap.capacity.sampling`     Monte Carlo workspace (joint samples, voxel fill)
- :mod:`~capmap.capacity.engine`       exact dynamic load-carrying capacity of configurations and points
- :mod:`~capmap.capacity.voxels`       the voxel grid and per-voxel minima
- :mod:`~capmap.capacity.planning`     improved A* through the voxels that carry the payload
- :mod:`~capmap.capacity.branch_planning` A* over (voxel, IK branch) states: plans on the branch that is executed
- :mod:`~capmap.capacity.branch_moves` tracking a branch along moves, their capacity, the search's IK caches
- :mod:`~capmap.capacity.search`       the searches' contract: start, goal, payload -> plan or reason
- :mod:`~capmap.capacity.verification` the real motion along a path: loads, segment capacities, verdicts
- :mod:`~capmap.capacity.tables`       the family's tables and column schemas (model, points, capacities, voxels)
- :mod:`~capmap.capacity.gain`         the plan-gain experiment (isotropic vs direction-aware moves, verified)
- :mod:`~capmap.capacity.atlas`        one coarse map per (locked joint, angle) and its summary rows
- :mod:`~capmap.capacity.baseline`     the healthy arm: the failed joint swept, the best posture per point
- :mod:`~capmap.capacity.self_motion`  the healthy arm's data: its angles, question, answer, postures' capacity
- :mod:`~capmap.capacity.angle_search` between the grid angles: a best posture followed along its IK branch
- :mod:`~capmap.capacity.refine`       voxel minima refined until they converge, all branches and each configuration
- :mod:`~capmap.capacity.refine_data`  the refinement's settings, point results and per-voxel minima (plain data)
- :mod:`~capmap.capacity.folds`        the refinement's fold brackets (singular surfaces crossing a voxel)
- :mod:`~capmap.capacity.patterns`     the refinement's local-search points (corners, compass)
- :mod:`~capmap.capacity.query`        questions answered directly: a point on every configuration, a line on one
"""

from capmap._lazy import lazy_exports

_EXPORTS = {
    'directions': 'directions',
    'engine': 'engine',
    'planning': 'planning',
    'branch_planning': 'branch_planning',
    'branch_moves': 'branch_moves',
    'search': 'search',
    'plan_on_branch': 'branch_planning',
    'sampling': 'sampling',
    'verification': 'verification',
    'voxels': 'voxels',
    'tables': 'tables',
    'gain': 'gain',
    'atlas': 'atlas',
    'refine': 'refine',
    'refine_data': 'refine_data',
    'query': 'query',
    'point_query': 'query',
    'line_query': 'query',
    'LoadLimits': 'engine',
    'Motion': 'engine',
    'point_capacity': 'problem',
    'plan': 'planning',
    'judge': 'verification',
    'verify_path': 'verification',
    'Grid': 'voxels',
    'voxelise': 'voxels',
}

__all__ = [
    "Grid",
    "line_query",
    "point_query",
    "query",
    "refine",
    "refine_data",
    "LoadLimits",
    "Motion",
    "directions",
    "engine",
    "judge",
    "plan",
    "plan_on_branch",
    "branch_planning",
    "branch_moves",
    "planning",
    "point_capacity",
    "sampling",
    "search",
    "verification",
    "verify_path",
    "voxelise",
    "voxels",
    "tables",
    "gain",
    "atlas",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
