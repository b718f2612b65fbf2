"""Stages of the voxel refinement: refine (shard k of n of the reachable voxels: each voxel's
minimum refined until it converges, :mod:`capmap.capacity.refine`) -> voxel_map (the sampled
voxels with the refined values: the map every later stage reads)."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from capmap.capacity.directions import grid_axes
from capmap.capacity.engine import SINGULAR, point_capacity
from capmap.capacity.refine import Evaluation, VoxelMinima, refine
from capmap.capacity.tables import AXIS_COLUMNS, grid_of
from capmap.core import ik
from capmap.core.configuration import arm_configurations
from capmap.core.dynamics import ArmDynamics
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.stages.arm import arm_task_from
from capmap.stages.common import stage_config

__all__ = ["REFINED_COLUMNS", "CONFIGURATION_COLUMNS", "stage_refine", "stage_voxel_map"]

REFINED_COLUMNS = ["capacity_kg", "binding", "n_points", "n_reachable", "last_change_rel", "converged",
                   "worst_x_m", "worst_y_m", "worst_z_m", *AXIS_COLUMNS]
# voxels/configurations.parquet: one row per voxel x configuration that a point of the voxel holds
CONFIGURATION_COLUMNS = ["i", "j", "k", "x_m", "y_m", "z_m", "configuration", "capacity_kg", "binding", "n_points",
                         "converged", "worst_x_m", "worst_y_m", "worst_z_m", *AXIS_COLUMNS]


def stage_refine(voxels: str, out: str, out_configurations: str, slice_json: str, shard: int, shards: int) -> None:
    """Refine shard ``shard`` of the reachable voxels (in flat-index order, ``shards`` slabs of equal count:
    a slab's voxels share their corners and faces), all branches and each configuration; write one row
    per voxel (``out``) and one per voxel x configuration met there (``out_configurations``)."""
    cfg = stage_config(slice_json)
    log = stage_logger(__name__, f"refine shard {shard} of {shards}")
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
    mine = vox[vox.n_reachable > 0]
    mine = mine.iloc[np.argsort(grid.flat(mine[["i", "j", "k"]].to_numpy()), kind="stable")]
    cut = np.linspace(0, len(mine), shards + 1).round().astype(int)  # slabs: neighbours share their corners
    mine = mine.iloc[cut[shard]:cut[shard + 1]]

    dyn, axes, labels = ArmDynamics(arm), grid_axes(), arm_configurations(arm)

    def evaluate(points: np.ndarray, *_) -> Evaluation:  # every value exact (the ceiling and owner not used)
        parts = []
        for r in range(0, len(points), 2000):
            sol = ik.solve(arm, points[r:r + 2000], rotation)
            pc = point_capacity(dyn, sol.q, sol.n_solutions, dirs, motion, limits, axes, labels)
            parts.append(Evaluation(pc.capacity_kg, pc.axis_capacity_kg, pc.binding, sol.n_solutions,
                                    pc.config_capacity_kg, pc.config_axis_capacity_kg, pc.config_binding, pc.config_branches))
        return Evaluation(*(np.concatenate([getattr(e, f) for e in parts]) for f in Evaluation.__dataclass_fields__))

    start = VoxelMinima.with_configurations(len(labels.names),
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
    write_configurations(res, grid, labels, names, out_configurations,
                         datasets.provenance("refine", cfg.doc, shard=shard, shards=shards,
                                             configurations=list(labels.names), labels=labels.description))
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


def write_configurations(res: VoxelMinima, grid, labels, limit_names: list[str], out: str, meta: dict) -> None:
    """One row per voxel x configuration held by some evaluated point of the voxel."""
    v, c = np.nonzero(np.isfinite(res.config_capacity_kg))
    i, j, k = np.unravel_index(res.voxel[v], grid.shape)
    centre = grid.centres(np.stack([i, j, k], axis=1)) if len(v) else np.zeros((0, 3))
    w = res.config_worst_m[v, c]
    df = pd.DataFrame({"i": i, "j": j, "k": k, "x_m": centre[:, 0], "y_m": centre[:, 1], "z_m": centre[:, 2],
                       "configuration": pd.Categorical.from_codes(c, list(labels.names)),
                       "capacity_kg": res.config_capacity_kg[v, c],
                       "binding": np.array(limit_names + [""])[res.config_binding[v, c]],
                       "n_points": res.config_n_points[v, c], "converged": res.converged[v],
                       "worst_x_m": w[:, 0], "worst_y_m": w[:, 1], "worst_z_m": w[:, 2]})
    for a, col in enumerate(AXIS_COLUMNS):
        df[col] = res.config_axis_capacity_kg[v, c, a]
    datasets.write(df[CONFIGURATION_COLUMNS], out, meta)


def stage_voxel_map(sampled: str, refined: list[str], configurations: list[str], out: str, out_configurations: str,
                    slice_json: str) -> None:
    """The sampled voxel table with each refined voxel's values (``capacity_sampled_kg`` keeps the
    sampled minimum); without refinement (``voxels.refine: false``) the sampled table as is. The
    per-configuration shards gathered into ``out_configurations`` (no rows without refinement: the
    configuration maps are the refinement's)."""
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
    parts = [datasets.read(p) for p in configurations]
    names = parts[0].attrs["capmap"]["configurations"] if parts else []
    conf = (pd.concat(parts, ignore_index=True) if parts else pd.DataFrame({c: [] for c in CONFIGURATION_COLUMNS}))
    conf = conf.sort_values(["i", "j", "k", "configuration"], ignore_index=True) if len(conf) else conf
    if len(conf):
        conf["configuration"] = pd.Categorical(conf.configuration.astype(str), categories=names)
        conf["binding"] = conf.binding.astype("category")
    datasets.write(conf[CONFIGURATION_COLUMNS], out_configurations, datasets.provenance(
        "voxels", cfg.doc, grid=vox.attrs["capmap"]["grid"], refined=bool(refined), configurations=names,
        labels=parts[0].attrs["capmap"]["labels"] if parts else ""))
    reach = vox.n_reachable > 0
    drop = (vox.capacity_sampled_kg - vox.capacity_kg)[reach] / vox.capacity_sampled_kg[reach].where(
        vox.capacity_sampled_kg[reach] > 0, 1.0)
    stage_logger(__name__, "voxel map").info(
        f"{int(reach.sum())} reachable voxels, {int(vox.n_points.sum())} points; refined: {bool(refined)}"
        + (f", {int((reach & ~vox.converged).sum())} not converged, values lowered by up to {100 * drop.max():.1f} %"
           if refined else "") + f" -> {out}")
