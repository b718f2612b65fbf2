"""Stage of the failure-tolerant map: the least capacity over every joint's lock sweep, its summary per task
payload and its figure beside the healthy arm's map."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.capacity.tolerant import failure_tolerant, lock_reach, scopes, tolerance_summary
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.tolerant import TolerantContext, tolerant_figure
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_tolerant"]


def stage_tolerant(sweep_paths: list[str], out: Outputs, slice_json: str) -> None:
    """The failure-tolerant map over every joint's sweep, its summary per task payload and its figure
    beside the healthy arm's map."""
    cfg = stage_config(slice_json)
    run = cfg.run
    sweeps = pd.concat([datasets.read(p) for p in sweep_paths], ignore_index=True)
    grid = datasets.read_provenance(sweep_paths[0])["grid"]
    tol = failure_tolerant(sweeps)
    summary = tolerance_summary(tol, float(grid["edge_m"]), run.task.payload_kg)
    worst = lock_reach(sweeps).iloc[0]
    prov = datasets.provenance("tolerant", cfg.doc, grid=grid)
    datasets.write(tol, out["tolerant"], prov)
    datasets.write(summary, out["summary"], prov)
    tolerant_figure(tol, TolerantContext(grid, tuple(run.task.payload_kg), (int(worst.joint), float(worst.angle_deg),
                                                                           int(worst.n_reached)),
                                         scopes(tol), np.asarray(run.failure.start_m), np.asarray(run.task.goal_m)),
                    out["figure"])
    log = stage_logger(__name__, "failure-tolerant map")
    log.info(f"{int(tol.reachable_every_failure.sum())} of {len(tol)} voxels reachable whatever joint fails at whatever "
             f"swept angle; the lock reaching fewest: joint {int(worst.joint)} at {worst.angle_deg:g} deg, "
             f"{int(worst.n_reached)} voxels")
    for r in summary.itertuples():
        log.info(f"{r.scope}: {r.payload_kg:g} kg carried in {r.volume_m3:,.1f} m^3 (reached {r.reachable_m3:,.1f} m^3)")
