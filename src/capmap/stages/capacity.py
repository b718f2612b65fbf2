"""Stages of the capacity map: model -> sample -> capacity (sharded) -> voxels -> summary.

Each function is what one Snakemake rule runs: file paths in and out, and ``slice_json``,
the canonical JSON of the config slice the stage depends on (recorded as provenance).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.capacity.build import capacity_problem
from capmap.capacity.tables import axes_stored, capacity_table, grid_meta, model_table, sample_table, voxel_table
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.robots import load, run_arm
from capmap.stages.common import stage_config

__all__ = ["stage_model", "stage_sample", "stage_capacity", "stage_points", "stage_voxels"]


# --------------------------------------------------------------------------- model


def stage_model(robot_yaml: str, out: str, slice_json: str) -> None:
    sc = stage_config(slice_json)
    robot = load(robot_yaml)
    df = model_table(robot)
    datasets.write(df, out, datasets.provenance("model", sc.doc, robot=robot.name,
                                                 gravity_mps2=robot.gravity.tolist(), base_com_m=robot.base_com.tolist()))
    log = stage_logger(__name__, "model")
    log.info(f"{robot.name}: {robot.n_joints} joints, total mass {df.mass_kg.sum():.1f} kg "
             + (f"(drives: rotor inertia {df.armature_kgm2.min():g}-{df.armature_kgm2.max():g} kg m^2, in the capacity "
                "map) " if df.armature_kgm2.any() else "") + f"-> {out}")
    if robot.has_friction:
        log.warning(f"{robot.name}'s drives have friction (Coulomb up to {df.coulomb_nm.max():g} N m): the capacity map "
                    "leaves it out (its sign follows each joint's direction of motion, which changes across the sphere "
                    "of motion directions); for a map that holds with it, lower limits.joint_torque_nm by each joint's "
                    "friction at the task's speed (Coulomb + viscous x joint speed)")


# --------------------------------------------------------------------------- sample


def stage_sample(out: str, slice_json: str) -> None:
    cfg = stage_config(slice_json)
    log = stage_logger(__name__, "sample")
    arm = run_arm(cfg.run)
    sc = cfg.run.sampling
    df = sample_table(arm, sc, cfg.run.voxel_edge_m if sc.mode == "voxel_fill" else None, log)
    datasets.write(df, out, datasets.provenance("sample", cfg.doc, seed=sc.seed))
    log.info(f"{len(df)} points ({sc.n_points} joint samples, mode {sc.mode}, seed {sc.seed}) -> {out}")


# --------------------------------------------------------------------------- capacity


def stage_capacity(points: str, out: str, slice_json: str, shard: int, shards: int) -> None:
    """Shard ``shard`` (0-based) of ``shards``: points with point_id % shards == shard."""
    cfg = stage_config(slice_json)
    log = stage_logger(__name__, f"capacity shard {shard} of {shards}")
    problem = capacity_problem(cfg.run)  # limits checked before the long work
    dirs = problem.directions
    pts = datasets.read(points)
    mine = pts[pts.point_id % shards == shard]
    log.info(f"{len(mine)} of {len(pts)} points, {len(dirs)} directions ({dirs.kind})")
    df = capacity_table(problem, mine.point_id.to_numpy(), mine[["x_m", "y_m", "z_m"]].to_numpy(), log)
    datasets.write(df, out, datasets.provenance("capacity", cfg.doc, seed=cfg.run.sampling.seed,
                                                 shard=shard, shards=shards, directions=dirs.kind))
    n_reach = int(df.reachable.sum()) if len(df) else 0
    log.info(f"done: {n_reach} reachable, min capacity "
             f"{np.nanmin(df.capacity_kg) if n_reach else float('nan'):.1f} kg -> {out}")


# --------------------------------------------------------------------------- voxels


def stage_points(shards: list[str], out: str, slice_json: str) -> None:
    """The capacity shards gathered into one per-point table, by point_id (the shards are temporary)."""
    cfg = stage_config(slice_json)
    parts = [datasets.read(p) for p in shards]
    pts = pd.concat(parts, ignore_index=True).sort_values("point_id", ignore_index=True)
    dirs = parts[0].attrs["capmap"].get("directions") if parts else None
    prov = datasets.provenance("capacity", cfg.doc, seed=cfg.run.sampling.seed, shards=len(shards), directions=dirs)
    datasets.write(axes_stored(pts), out, prov)
    stage_logger(__name__, "points").info(f"{len(pts)} points ({int(pts.reachable.sum())} reachable) from "
                                          f"{len(shards)} shards -> {out}")


def stage_voxels(points: str, out_voxels: str, slice_json: str) -> None:
    """The sampled voxel map: each voxel the least capacity over its sampled points."""
    cfg = stage_config(slice_json)
    pts = datasets.read(points)
    vox, grid = voxel_table(pts, cfg.run.voxel_edge_m)
    meta = grid_meta(grid)
    datasets.write(vox, out_voxels, datasets.provenance("voxels", cfg.doc, seed=cfg.run.sampling.seed, grid=meta))
    reach = vox.n_reachable > 0
    stage_logger(__name__, "voxels").info(
        f"grid {grid.shape} x {grid.edge_m} m: {int(reach.sum())} reachable voxels of {grid.n_voxels}; "
        f"{int((vox.n_points == 0).sum())} voxels without any sample; {len(pts)} points -> {out_voxels}")


# --------------------------------------------------------------------------- summary


