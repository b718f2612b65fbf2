"""Stages of the fault atlas: one coarse capacity map per (locked joint, lock angle), each a
cached job keyed by its wildcards, then the atlas table, the capacity-volume curves and
their figures. The task, limits and robot are the run's; the start configuration of each
map is resolved as for the main run (the IK branch at the start nearest to task.q_ini_deg)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.capacity import planning
from capmap.capacity.verification import judge, verify_path
from capmap.capacity.voxels import capacity_volume
from capmap.config.capacity import LockConfig
from capmap.config.failure import locked_arm, resolve_failure
from capmap.config.robot_file import load
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.errors import CapmapError
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.atlas import atlas_curves_figure, atlas_heatmap
from capmap.stages.capacity import capacity_table, grid_meta, sample_table, voxel_table
from capmap.stages.common import stage_config
from capmap.stages.verify import PLAN_KEYS

__all__ = ["stage_atlas_map", "stage_atlas", "CURVE_POINTS"]

CURVE_POINTS = 101  # payloads of the capacity-volume curves, 0 .. the largest voxel capacity of the atlas


def stage_atlas_map(out_voxels: str, out_summary: str, slice_json: str, joint: int, angle_deg: float) -> None:
    """The capacity map of the arm with ``joint`` locked at ``angle_deg`` and its summary rows
    (one per task payload): reachable volume, capacity quantiles, volume carrying the payload,
    the direct line's capacity and whether a plan exists."""
    cfg = stage_config(slice_json)
    run = cfg.run
    log = stage_logger(__name__, f"atlas joint {joint} at {angle_deg:g} deg")
    robot = load(run.robot)
    sc = run.atlas.sampling
    dirs = run.atlas.directions.build()
    edge = run.atlas.edge_m
    task = run.task
    arm = locked_arm(robot, joint, angle_deg)
    limits = run.limits.resolve(robot.n_joints).for_arm(arm)
    motion, rotation = task.motion, task.rotation
    log.info(f"IK method {ik.method_for(arm.chain)}; {len(dirs)} directions; edge {edge} m")
    pts = sample_table(arm, sc, edge, log)
    cap = capacity_table(arm, pts.point_id.to_numpy(), pts[["x_m", "y_m", "z_m"]].to_numpy(), rotation, motion,
                         limits, dirs, log, chunk=1000)
    vox, grid = voxel_table(cap, edge)
    reach = vox.capacity_kg[vox.n_reachable > 0].to_numpy()
    q = np.quantile(reach, [0.0, 0.05, 0.5, 0.95, 1.0]) if len(reach) else np.full(5, np.nan)
    base = {"joint": joint, "angle_deg": float(angle_deg), "ik_method": ik.method_for(arm.chain),
            "reachable_volume_m3": len(reach) * edge**3, "capacity_min_kg": q[0], "capacity_p5_kg": q[1],
            "capacity_median_kg": q[2], "capacity_p95_kg": q[3], "capacity_max_kg": q[4]}
    start_note, q_start = "", None
    try:
        failure = resolve_failure(robot, LockConfig(joint, angle_deg), task)
        q_start = np.deg2rad(np.asarray(failure.q_start_deg))[arm.active]
        base["start_branch_offset_deg"] = failure.offset_deg
    except CapmapError as exc:
        start_note = f"start: {exc}".replace("config: ", "")
        base["start_branch_offset_deg"] = np.nan
    base["start_reachable"] = q_start is not None
    start, goal = np.asarray(task.start_m, dtype=float), np.asarray(task.goal_m, dtype=float)
    direct = None
    if q_start is not None:
        try:
            direct = verify_path(ArmDynamics(arm), np.array([start, goal]), rotation, q_start, motion,
                                 run.verification.dt_s, limits)
        except CapmapError as exc:
            start_note = f"direct line: {exc}"
    rows = []
    for payload in task.payload_kg:
        row = {**base, "payload_kg": payload, "volume_carrying_payload_m3": float(capacity_volume(reach, edge, [payload])[0])}
        if direct is not None:
            _, verdict = judge(direct, arm, limits, payload)
            row.update(direct_capacity_kg=verdict.capacity_kg, direct_feasible=verdict.feasible,
                       direct_note="" if verdict.feasible else (verdict.limits_exceeded_at_payload
                                                                or (verdict.tracking if verdict.tracking != "ok"
                                                                    else verdict.joint_range)))
        else:
            row.update(direct_capacity_kg=np.nan, direct_feasible=False, direct_note=start_note)
        try:
            p = planning.plan(grid, vox.capacity_kg.to_numpy(), start, goal, payload)
            row.update(plan_exists=True, plan_length_m=p.length_m, plan_note="")
        except CapmapError as exc:
            row.update(plan_exists=False, plan_length_m=np.nan, plan_note=exc.in_terms(**PLAN_KEYS))
        rows.append(row)
        log.info(f"{payload:g} kg: {row['volume_carrying_payload_m3']:.1f} m^3 carry it; direct line "
                 f"{row['direct_capacity_kg']:.1f} kg; plan {'found' if row['plan_exists'] else 'none'}")
    prov = datasets.provenance("atlas_map", cfg.doc, seed=sc.seed, joint=joint, angle_deg=float(angle_deg),
                               grid=grid_meta(grid))
    datasets.write(vox, out_voxels, prov)
    datasets.write(pd.DataFrame(rows), out_summary, prov)


def stage_atlas(summaries: list[str], voxels: list[str], out_atlas: str, out_curves: str, out_heatmap: str,
                out_curves_png: str, slice_json: str) -> None:
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
    datasets.write(atlas, out_atlas, prov)
    datasets.write(curves, out_curves, prov)
    atlas_heatmap(atlas, out_heatmap)
    atlas_curves_figure(curves, sorted(atlas.payload_kg.unique()), out_curves_png)
    stage_logger(__name__, "atlas").info(f"{atlas.joint.nunique()} joints x {atlas.angle_deg.nunique()} angles -> "
                                         f"{out_atlas}, {out_curves}")
