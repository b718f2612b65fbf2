"""Stages of the fault atlas: one coarse capacity map per (locked joint, lock angle), each a
cached job keyed by its wildcards, then the atlas table, the capacity-volume curves and
their figures. The task, limits and robot are the run's; the start configuration of each
map is resolved as for the main run (the IK branch at the start nearest to task.q_ini_deg)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from capmap.capacity.atlas import AtlasTask, atlas_map
from capmap.capacity.build import capacity_problem, resolve_failure
from capmap.capacity.tables import grid_meta
from capmap.capacity.voxels import capacity_volume
from capmap.config.capacity import LockConfig
from capmap.core import ik
from capmap.errors import CapmapError
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.atlas import atlas_curves_figure, atlas_heatmap
from capmap.stages.common import Outputs, stage_config
from capmap.stages.verify import PLAN_KEYS

__all__ = ["stage_atlas_map", "stage_atlas", "CURVE_POINTS"]

CURVE_POINTS = 101  # payloads of the capacity-volume curves, 0 .. the largest voxel capacity of the atlas


def stage_atlas_map(out_voxels: str, out_summary: str, slice_json: str, joint: int, angle_deg: float) -> None:
    """The capacity map of the arm with ``joint`` locked at ``angle_deg`` and its summary rows
    (one per task payload): reachable volume, capacity quantiles, volume carrying the payload,
    the direct line's capacity and whether a plan exists (:func:`capmap.capacity.atlas.atlas_map`)."""
    cfg = stage_config(slice_json)
    run = cfg.run
    log = stage_logger(__name__, f"atlas joint {joint} at {angle_deg:g} deg")
    problem = capacity_problem(run, joint, angle_deg, run.atlas.directions)
    arm, task = problem.arm, run.task
    log.info(f"IK method {ik.method_for(arm.chain)}; {len(problem.directions)} directions; edge {run.atlas.edge_m} m")
    start_note, q_start, offset = "", None, np.nan
    try:  # the start configuration on this lock, as for the main run
        failure, _ = resolve_failure(arm.robot, LockConfig(joint, angle_deg), replace(task, start_m=run.failure.start_m))
        q_start = np.deg2rad(np.asarray(failure.q_start_deg))[arm.active]
        offset = failure.offset_deg
    except CapmapError as exc:
        start_note = f"start: {exc}".replace("config: ", "")
    at = AtlasTask(np.asarray(run.failure.start_m, dtype=float), np.asarray(task.goal_m, dtype=float), task.payload_kg,
                   run.verification.dt_s, q_start, offset, start_note)
    res = atlas_map(problem, (joint, angle_deg), run.atlas.sampling, run.atlas.edge_m, at,
                    lambda exc: exc.in_terms(**PLAN_KEYS), log)
    prov = datasets.provenance("atlas_map", cfg.doc, seed=run.atlas.sampling.seed, joint=joint,
                               angle_deg=float(angle_deg), grid=grid_meta(res.grid))
    datasets.write(res.voxels, out_voxels, prov)
    datasets.write(pd.DataFrame(res.rows), out_summary, prov)


def stage_atlas(summaries: list[str], voxels: list[str], out: Outputs, slice_json: str) -> None:
    """The atlas table (one row per joint x angle x task payload), the capacity-volume curves on a
    common payload axis, a heat map and the curves' figure."""
    doc = stage_config(slice_json).doc
    atlas = pd.concat([datasets.read(p) for p in summaries], ignore_index=True)
    atlas = atlas.sort_values(["joint", "angle_deg", "payload_kg"], ignore_index=True)
    maps = [datasets.read(p) for p in voxels]
    top = max([float(np.nanmax(v.capacity_kg)) for v in maps if np.isfinite(v.capacity_kg).any()] or [1.0])
    payloads = np.linspace(0.0, top, CURVE_POINTS)
    curves = []
    for v in maps:
        meta = v.attrs["capmap"]
        reach = v.capacity_kg[v.n_reachable > 0].to_numpy()
        curves.append(pd.DataFrame({"joint": meta["joint"], "angle_deg": meta["angle_deg"], "payload_kg": payloads,
                                    "volume_m3": capacity_volume(reach, meta["grid"]["edge_m"], payloads)}))
    curves = pd.concat(curves, ignore_index=True).sort_values(["joint", "angle_deg", "payload_kg"], ignore_index=True)
    prov = datasets.provenance("atlas", doc)
    datasets.write(atlas, out["atlas"], prov)
    datasets.write(curves, out["curves"], prov)
    atlas_heatmap(atlas, out["heatmap"])
    atlas_curves_figure(curves, sorted(atlas.payload_kg.unique()), out["curves_png"])
    stage_logger(__name__, "atlas").info(f"{atlas.joint.nunique()} joints x {atlas.angle_deg.nunique()} angles -> "
                                         f"{out['atlas']}, {out['curves']}")
