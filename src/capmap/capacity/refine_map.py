"""The voxel map's refinement as tables: one shard of the sampled map's reachable voxels refined
(:func:`capmap.capacity.refine.refine` with the locked arm's evaluator), and the shards merged into
the map every later stage reads; the column schemas of these tables. No file I/O."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from capmap.capacity.engine import SINGULAR
from capmap.capacity.evaluator import LockedEvaluator
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.refine import RefineSettings, VoxelMinima, refine
from capmap.capacity.refine_data import BATCH_VOXELS
from capmap.capacity.tables import AXIS_COLUMNS, grid_of
from capmap.capacity.voxels import Grid

__all__ = ["REFINED_COLUMNS", "CONFIGURATION_COLUMNS", "RefinedShard", "refine_shard", "merge_refined"]

REFINED_COLUMNS = ["capacity_kg", "binding", "n_points", "n_reachable", "last_change_rel", "converged",
                   "worst_x_m", "worst_y_m", "worst_z_m", *AXIS_COLUMNS]
# voxels/configurations.parquet: one row per voxel x configuration that a point of the voxel holds
CONFIGURATION_COLUMNS = ["i", "j", "k", "x_m", "y_m", "z_m", "configuration", "capacity_kg", "binding", "n_points",
                         "converged", "worst_x_m", "worst_y_m", "worst_z_m", *AXIS_COLUMNS]




@dataclass(frozen=True)
class RefinedShard:
    """A refined shard: ``voxels`` (one row per voxel: i, j, k and :data:`REFINED_COLUMNS`),
    ``configurations`` (:data:`CONFIGURATION_COLUMNS`), the refinement's rounds (the most of any batch) and
    points evaluated, and the start's values ``start_kg`` (V,) (for the log: how far the refinement
    lowered them)."""

    voxels: pd.DataFrame
    configurations: pd.DataFrame
    rounds: int
    n_evaluated: int
    start_kg: np.ndarray

    @property
    def capacity_kg(self) -> np.ndarray:
        return self.voxels.capacity_kg.to_numpy()

    @property
    def converged(self) -> np.ndarray:
        return self.voxels.converged.to_numpy()


def refine_shard(vox: pd.DataFrame, problem: CapacityProblem, settings: RefineSettings, shard: int, shards: int,
                 rng: np.random.Generator, log) -> RefinedShard:
    """Refine shard ``shard`` of the reachable voxels of the sampled map ``vox`` (in flat-index order,
    ``shards`` slabs of equal count: a slab's voxels share their corners and faces), all branches and
    each configuration of ``problem`` (it must carry its ``labels``); progress to ``log`` per round. The
    slab is refined in batches of :data:`BATCH_VOXELS` consecutive voxels, one after the other from the same
    ``rng`` (each voxel's value needs only its own points: a point two batches share is evaluated by
    each), so that a job's memory does not grow with its slab."""
    grid = grid_of(vox)
    mine = vox[vox.n_reachable > 0]
    mine = mine.iloc[np.argsort(grid.flat(mine[["i", "j", "k"]].to_numpy()), kind="stable")]
    cut = np.linspace(0, len(mine), shards + 1).round().astype(int)  # slabs: neighbours share their corners
    mine = mine.iloc[cut[shard]:cut[shard + 1]]
    parts = [_refine_batch(mine.iloc[b:b + BATCH_VOXELS], grid, problem, settings, rng, log, (b, len(mine)))
             for b in range(0, len(mine), BATCH_VOXELS)]
    if not parts:
        parts = [_refine_batch(mine, grid, problem, settings, rng, log, (0, 0))]
    return RefinedShard(pd.concat([p.voxels for p in parts], ignore_index=True),
                        pd.concat([p.configurations for p in parts], ignore_index=True),
                        max(p.rounds for p in parts), sum(p.n_evaluated for p in parts),
                        np.concatenate([p.start_kg for p in parts]))


def _refine_batch(mine: pd.DataFrame, grid: Grid, problem: CapacityProblem, settings: RefineSettings,
                  rng: np.random.Generator, log, where: tuple[int, int]) -> RefinedShard:
    """One batch of a shard's voxels (``mine``: rows of the sampled table) refined; ``where``: (its first
    voxel, the shard's voxels), for the progress lines."""
    labels = problem.labels
    names = list(problem.limits.names) + [SINGULAR]
    index = {n: i for i, n in enumerate(names)}
    start = VoxelMinima.with_configurations(len(labels.names),
        voxel=grid.flat(mine[["i", "j", "k"]].to_numpy()), capacity_kg=mine.capacity_kg.to_numpy(),
        axis_capacity_kg=mine[AXIS_COLUMNS].to_numpy(), n_points=mine.n_points.to_numpy(),
        n_reachable=mine.n_reachable.to_numpy(), last_change=np.zeros(len(mine)),
        converged=np.zeros(len(mine), dtype=bool), worst_m=mine[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy(),
        binding=mine.binding.astype(str).map(index).fillna(-1).astype(int).to_numpy(), rounds=0, n_evaluated=0)
    t0 = time.perf_counter()
    batch = f"voxels {where[0] + 1}-{where[0] + len(mine)} of {where[1]}: " if len(mine) < where[1] else ""

    def progress(rnd: int, active: int, points: int) -> None:
        log.info(f"{batch}round {rnd}: {active} of {len(mine)} voxels not converged, {points} new points "
                 f"({time.perf_counter() - t0:.1f} s so far)")

    res = refine(grid, start, LockedEvaluator(problem), settings, rng, progress)
    i, j, k = np.unravel_index(res.voxel, grid.shape)
    df = pd.DataFrame({"i": i, "j": j, "k": k, "capacity_kg": res.capacity_kg,
                       "binding": np.array(names + [""])[res.binding], "n_points": res.n_points,
                       "n_reachable": res.n_reachable, "last_change_rel": res.last_change, "converged": res.converged,
                       "worst_x_m": res.worst_m[:, 0], "worst_y_m": res.worst_m[:, 1], "worst_z_m": res.worst_m[:, 2]})
    for c, col in enumerate(AXIS_COLUMNS):
        df[col] = res.axis_capacity_kg[:, c]
    return RefinedShard(df, _configuration_table(res, grid, list(labels.names), names), res.rounds, res.n_evaluated,
                        start.capacity_kg)


def _configuration_table(res: VoxelMinima, grid: Grid, configurations: list[str], limit_names: list[str]) -> pd.DataFrame:
    """One row per voxel x configuration held by some evaluated point of the voxel."""
    v, c = np.nonzero(np.isfinite(res.config_capacity_kg))
    i, j, k = np.unravel_index(res.voxel[v], grid.shape)
    centre = grid.centres(np.stack([i, j, k], axis=1)) if len(v) else np.zeros((0, 3))
    w = res.config_worst_m[v, c]
    df = pd.DataFrame({"i": i, "j": j, "k": k, "x_m": centre[:, 0], "y_m": centre[:, 1], "z_m": centre[:, 2],
                       "configuration": pd.Categorical.from_codes(c, configurations),
                       "capacity_kg": res.config_capacity_kg[v, c],
                       "binding": np.array(limit_names + [""])[res.config_binding[v, c]],
                       "n_points": res.config_n_points[v, c], "converged": res.converged[v],
                       "worst_x_m": w[:, 0], "worst_y_m": w[:, 1], "worst_z_m": w[:, 2]})
    for a, col in enumerate(AXIS_COLUMNS):
        df[col] = res.config_axis_capacity_kg[v, c, a]
    return df[CONFIGURATION_COLUMNS]


def merge_refined(vox: pd.DataFrame, refined: list[pd.DataFrame], configurations: list[pd.DataFrame],
                  names: list[str]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The sampled voxel table ``vox`` with each refined voxel's values (``capacity_sampled_kg`` keeps the
    sampled minimum; no refined shards: the sampled table as is), and the per-configuration shards
    gathered (``names``: the configurations, in order; no rows without refinement)."""
    grid = grid_of(vox)
    vox["capacity_sampled_kg"] = vox.capacity_kg
    vox["last_change_rel"] = np.nan
    vox["converged"] = False
    if refined:
        ref = pd.concat(refined, ignore_index=True)
        rows = grid.flat(ref[["i", "j", "k"]].to_numpy())  # the table is in C order: flat index = row
        vox["binding"] = vox.binding.astype(str)
        for col in REFINED_COLUMNS:
            vox.loc[rows, col] = ref[col].to_numpy()
        vox["binding"] = vox.binding.astype("category")
    conf = (pd.concat(configurations, ignore_index=True) if configurations
            else pd.DataFrame({c: [] for c in CONFIGURATION_COLUMNS}))
    conf = conf.sort_values(["i", "j", "k", "configuration"], ignore_index=True) if len(conf) else conf
    if len(conf):
        conf["configuration"] = pd.Categorical(conf.configuration.astype(str), categories=names)
        conf["binding"] = conf.binding.astype("category")
    return vox, conf[CONFIGURATION_COLUMNS]
