"""Stage of a joint's lock sweep: the maps of the arm with the joint locked at every swept angle, on the
healthy arm's points (one grid for every lock of every joint), read by the advice and the failure-tolerant map."""

from __future__ import annotations

from capmap.capacity.build import capacity_problem
from capmap.capacity.healthy_map import healthy_samples
from capmap.capacity.lock_sweep import lock_angles, lock_sweep
from capmap.capacity.tables import grid_meta
from capmap.capacity.voxels import Grid
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.robots import load
from capmap.stages.common import stage_config

__all__ = ["stage_lock_sweep"]


def stage_lock_sweep(out: str, slice_json: str, joint: int, stands_at_deg: float) -> None:
    """The maps of the arm with ``joint`` locked at every angle of its sweep (``advice.step_deg`` apart,
    through ``stands_at_deg``) on the healthy arm's points at the atlas' sampling and edge, over the run's
    directions."""
    cfg = stage_config(slice_json)
    run = cfg.run
    log = stage_logger(__name__, f"lock sweep joint {joint}")
    robot = load(run.robot)
    angles = lock_angles(robot, joint, stands_at_deg, run.advice.step_deg)
    points, _ = healthy_samples(robot, run.atlas.sampling, run.atlas.edge_m)
    log.info(f"{len(angles)} angles {angles.min():g}..{angles.max():g} deg, {len(points)} points, "
             f"edge {run.atlas.edge_m} m, directions {run.directions.kind}")
    sweep = lock_sweep(lambda a: capacity_problem(run, joint, a), joint, angles, points,
                       run.atlas.edge_m, log)
    grid = Grid.covering(points, run.atlas.edge_m)
    datasets.write(sweep, out, datasets.provenance("lock_sweep", cfg.doc, seed=run.atlas.sampling.seed, joint=joint,
                                                   stands_at_deg=float(stands_at_deg), grid=grid_meta(grid)))
