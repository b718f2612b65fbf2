"""Figures of the verified motions (kept apart so that the planning and verification jobs do not
import matplotlib)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.capacity.build import configuration_name
from capmap.capacity.directions import GRID_AXES
from capmap.capacity.tables import AXIS_COLUMNS, configuration_voxels, grid_of
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.capacity_loads import load_series
from capmap.plots.capacity_paths import workspace_paths
from capmap.plots.palette import PATH_COLOURS
from capmap.robots import run_arm
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_verify_plots", "under_path"]

def under_path(main: pd.DataFrame, ts: pd.DataFrame) -> pd.DataFrame:
    """``ts`` (index 0..n-1) with, per sample, ``distance_m`` travelled along its path, its segment's
    capacity ``segment_capacity_kg`` (the least over the segment's tracked states, as the verification's
    segments table) and the map ``main``'s values of the voxel it is in: ``voxel_kg`` (its least over every
    direction) and ``voxel_along_kg`` (along the grid axis nearest the direction of the sample's segment,
    start to end); NaN outside the grid or where the map does not reach."""
    grid = grid_of(main)
    idx = grid.index(ts[["x_m", "y_m", "z_m"]].to_numpy())
    inside = idx[:, 0] >= 0
    rows = np.where(inside, grid.flat(np.maximum(idx, 0)), 0)
    reached = inside & (main.n_reachable.to_numpy()[rows] > 0)
    axes = GRID_AXES / np.linalg.norm(GRID_AXES, axis=1, keepdims=True)
    along, seg = np.full(len(ts), np.nan), np.full(len(ts), np.nan)
    table = main[AXIS_COLUMNS].to_numpy(float)
    tracked = ts.tracked.to_numpy(bool) if "tracked" in ts else np.ones(len(ts), bool)
    for _, g in ts.groupby(["path", "segment"], observed=True, sort=False):
        pos = g.index.to_numpy()
        d = np.diff(g[["x_m", "y_m", "z_m"]].to_numpy()[[0, -1]], axis=0)[0]
        axis = int(np.argmax(np.abs(axes @ d))) if np.linalg.norm(d) > 0 else 0
        along[pos] = table[rows[pos], axis]
        cap = g.state_capacity_kg.to_numpy(float)[tracked[pos]]
        seg[pos] = np.nanmin(cap) if np.isfinite(cap).any() else np.nan
    out = ts.copy()
    step = out.groupby("path", observed=True)[["x_m", "y_m", "z_m"]].diff().fillna(0.0).to_numpy()
    out["distance_m"] = pd.Series(np.linalg.norm(step, axis=1)).groupby(out.path.to_numpy()).cumsum().to_numpy()
    out["segment_capacity_kg"] = seg
    out["voxel_kg"] = np.where(reached, main.capacity_kg.to_numpy()[rows], np.nan)
    out["voxel_along_kg"] = np.where(reached, along, np.nan)
    return out


def stage_verify_plots(voxels: str, configurations: str, timeseries: str, out: Outputs, slice_json: str,
                       colour: str = PATH_COLOURS[0]) -> None:
    """The workspace of the verified task on the map of the start's configuration (``out["workspace"]``:
    does each path carry the payload, its own capacity against the map's voxels under it; the planned path in
    ``colour``, as on the summary map: :func:`capmap.plots.palette.path_colour`); torques, base force and base
    moment against their limits (``torques``, ``force``, ``moment``)."""
    vox, ts = datasets.read(voxels), datasets.read(timeseries)
    sc = stage_config(slice_json)
    name = configuration_name(run_arm(sc.run), sc.job.q_start_deg)
    op = configuration_voxels(vox, datasets.read(configurations), name)
    main = (vox if op is None else op).copy()
    main["capacity_best_axis_kg"] = main[AXIS_COLUMNS].max(axis=1)
    meta = ts.attrs["capmap"]
    payload, limits = meta["payload_kg"], meta["limits"]
    no_path = "" if meta.get("plan_status", "ok") == "ok" else meta.get("plan_reason", "")
    workspace_paths(main, under_path(main, ts.reset_index(drop=True)), payload, out["workspace"],
                    name if op is not None else "every IK branch", no_path, colour)
    for prefix, what, key in (("tau_", "Joint torques", "torques"), ("base_f", "Base disturbance force", "force"),
                              ("base_m", "Base disturbance moment", "moment")):
        load_series(ts, [c for c in limits if c.startswith(prefix)], limits, f"{what} carrying {payload:g} kg", out[key])
    stage_logger(__name__, f"verify plots {payload:g} kg").info("-> " + ", ".join(out.values()))
