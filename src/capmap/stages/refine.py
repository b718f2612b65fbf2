"""Stages of the voxel refinement: refine (shard k of n of the reachable voxels: each voxel's
minimum refined until it converges, :mod:`capmap.capacity.refine`) -> voxel_map (the sampled
voxels with the refined values: the map every later stage reads)."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from capmap.capacity.engine import SINGULAR
from capmap.capacity.refine import Evaluation, VoxelMinima, refine
from capmap.capacity.tables import AXIS_COLUMNS, capacity_table, grid_of
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.stages.arm import arm_task_from
from capmap.stages.common import stage_config

__all__ = ["REFINED_COLUMNS", "stage_refine", "stage_voxel_map"]

REFINED_COLUMNS = ["capacity_kg", "binding", "n_points", "n_reachable", "last_change_rel", "converged",
                   "worst_x_m", "worst_y_m", "worst_z_m", *AXIS_COLUMNS]


def stage_refine(voxels: str, out: str, slice_json: str, shard: int, shards: int) -> None:
    """Refine the reachable voxels with flat index % shards == shard; write one row per voxel."""
    cfg = stage_config(slice_json)
    log = stage_logger(__name__, f"refine shard {shard + 1}/{shards}")
    at = arm_task_from(cfg.run)
    arm, rotation, motion, limits = at.arm, at.rotation, at.motion, at.limits
    rf = cfg.run.refine
    settings = rf.settings(sorted(cfg.run.task.payload_kg))
    dirs = cfg.run.directions.build()
    names = list(limits.names) + [SINGULAR]
    index = {n: i for i, n in enumerate(names)}

    def codes(binding: pd.Series) -> np.ndarray:  # limit names -> their index (-1: none, unreachable)
        return binding.astype(str).map(index).fillna(-1).astype(int).to_numpy()

    vox = datasets.read(voxels)
    grid = grid_of(vox)
    flat = grid.flat(vox[["i", "j", "k"]].to_numpy())
    mine = vox[(flat % shards == shard) & (vox.n_reachable > 0).to_numpy()]

    def evaluate(points: np.ndarray) -> Evaluation:
        df = capacity_table(arm, np.arange(len(points)), points, rotation, motion, limits, dirs, chunk=2000)
        return Evaluation(df.capacity_kg.to_numpy(), df[AXIS_COLUMNS].to_numpy(), codes(df.binding),
                          df.n_branches.to_numpy())

    start = VoxelMinima(
        voxel=grid.flat(mine[["i", "j", "k"]].to_numpy()), capacity_kg=mine.capacity_kg.to_numpy(),
        axis_capacity_kg=mine[AXIS_COLUMNS].to_numpy(), n_points=mine.n_points.to_numpy(),
        n_reachable=mine.n_reachable.to_numpy(), last_change=np.zeros(len(mine)),
        converged=np.zeros(len(mine), dtype=bool), worst_m=mine[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy(),
        binding=codes(mine.binding),
        rounds=0, n_evaluated=0)
    t0 = time.perf_counter()

    def progress(rnd: int, active: int, points: int) -> None:
        log.info(f"round {rnd}: {active} of {len(mine)} voxels not converged, {points} new points "
                 f"({time.perf_counter() - t0:.1f} s so far)")

    rng = np.random.default_rng([rf.seed, shard, shards])
    res = refine(grid, start, evaluate, settings, rng, progress)
    i, j, k = np.unravel_index(res.voxel, grid.shape)
    df = pd.DataFrame({"i": i, "j": j, "k": k, "capacity_kg": res.capacity_kg,
                       "binding": np.array(names + [""])[res.binding], "n_points": res.n_points,
                       "n_reachable": res.n_reachable, "last_change_rel": res.last_change, "converged": res.converged,
                       "worst_x_m": res.worst_m[:, 0], "worst_y_m": res.worst_m[:, 1], "worst_z_m": res.worst_m[:, 2]})
    for c, col in enumerate(AXIS_COLUMNS):
        df[col] = res.axis_capacity_kg[:, c]
    datasets.write(df, out, datasets.provenance("refine", cfg.doc, shard=shard, shards=shards, rounds=res.rounds,
                                                 points_evaluated=res.n_evaluated))
    drop = (start.capacity_kg - res.capacity_kg) / np.where(start.capacity_kg > 0, start.capacity_kg, 1.0)
    log.info(f"done: {len(df)} voxels in {res.rounds} rounds, {res.n_evaluated} points evaluated "
             f"({res.n_evaluated / max(len(df), 1):.1f} per voxel), {int((~res.converged).sum())} not converged; "
             f"values lowered by up to {100 * np.max(drop, initial=0):.1f} % (median "
             f"{100 * np.median(drop) if len(drop) else 0:.2f} %) -> {out}")


def stage_voxel_map(sampled: str, refined: list[str], out: str, slice_json: str) -> None:
    """The sampled voxel table with each refined voxel's values (``capacity_sampled_kg`` keeps the
    sampled minimum); without refinement (``voxels.refine: false``) the sampled table as is."""
    cfg = stage_config(slice_json)
    vox = datasets.read(sampled)
    grid = grid_of(vox)
    vox["capacity_sampled_kg"] = vox.capacity_kg
    vox["last_change_rel"] = np.nan
    vox["converged"] = False
    if refined:
        ref = pd.concat([datasets.read(p) for p in refined], ignore_index=True)
        rows = grid.flat(ref[["i", "j", "k"]].to_numpy())  # the table is in C order: flat index = row
        vox["binding"] = vox.binding.astype(str)
        for col in REFINED_COLUMNS:
            vox.loc[rows, col] = ref[col].to_numpy()
        vox["binding"] = vox.binding.astype("category")
    datasets.write(vox, out, datasets.provenance("voxels", cfg.doc, grid=vox.attrs["capmap"]["grid"],
                                                  refined=bool(refined)))
    reach = vox.n_reachable > 0
    drop = (vox.capacity_sampled_kg - vox.capacity_kg)[reach] / vox.capacity_sampled_kg[reach].where(
        vox.capacity_sampled_kg[reach] > 0, 1.0)
    stage_logger(__name__, "voxel map").info(
        f"{int(reach.sum())} reachable voxels, {int(vox.n_points.sum())} points; refined: {bool(refined)}"
        + (f", {int((reach & ~vox.converged).sum())} not converged, values lowered by up to {100 * drop.max():.1f} %"
           if refined else "") + f" -> {out}")
