"""The voxel map's refinement as tables: one shard of the sampled map's reachable voxels refined
(:func:`capmap.capacity.refine.refine` with the locked arm's evaluator), and the shards merged into
the map every later stage reads; the column schemas of these tables. No file I/O."""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np
import pandas as pd

from capmap.capacity.engine import SINGULAR
from capmap.capacity.evaluator import LockedEvaluator
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.refine import RefineSettings, VoxelMinima, refine
from capmap.capacity.refine_data import BATCH_VOXELS
from capmap.capacity.tables import AXIS_COLUMNS, axes_stored, grid_of
from capmap.capacity.voxels import Grid
from capmap.errors import CapmapError

__all__ = ["REFINED_COLUMNS", "CONFIGURATION_COLUMNS", "RefinedBatch", "refine_shard", "merge_refined",
           "configuration_rows"]

REFINED_COLUMNS = ["capacity_kg", "binding", "n_points", "n_reachable", "last_change_rel", "converged",
                   "worst_x_m", "worst_y_m", "worst_z_m", *AXIS_COLUMNS]
# voxels/configurations.parquet: one row per voxel x configuration that a point of the voxel holds
CONFIGURATION_COLUMNS = ["i", "j", "k", "x_m", "y_m", "z_m", "configuration", "capacity_kg", "binding", "n_points",
                         "converged", "worst_x_m", "worst_y_m", "worst_z_m", *AXIS_COLUMNS]


@dataclass(frozen=True)
class RefinedBatch:
    """A refined batch of a shard's voxels: ``voxels`` (one row per voxel: i, j, k and :data:`REFINED_COLUMNS`),
    ``configurations`` (:data:`CONFIGURATION_COLUMNS`), the refinement's rounds and points evaluated,
    and the start's values ``start_kg`` (V,) (for the log: how far the refinement lowered them)."""

    voxels: pd.DataFrame
    configurations: pd.DataFrame
    rounds: int
    n_evaluated: int
    start_kg: np.ndarray


def refine_shard(vox: pd.DataFrame, problem: CapacityProblem, settings: RefineSettings, shard: int, shards: int,
                 rng: np.random.Generator, log) -> Iterator[RefinedBatch]:
    """Refine shard ``shard`` of the reachable voxels of the sampled map ``vox`` (in flat-index order,
    ``shards`` slabs of equal count: a slab's voxels share their corners and faces), all branches and
    each configuration of ``problem`` (it must carry its ``labels``); progress to ``log`` per round. The
    slab is refined in batches of :data:`BATCH_VOXELS` consecutive voxels, one after the other from the same
    ``rng`` (each voxel's value needs only its own points: a point two batches share is evaluated by
    each), each batch's tables yielded as it is done (in flat-index order; at least one, empty for an
    empty slab), so that a job's memory is bounded by a batch, not by its slab."""
    grid = grid_of(vox)
    mine = vox[vox.n_reachable > 0]
    mine = mine.iloc[np.argsort(grid.flat(mine[["i", "j", "k"]].to_numpy()), kind="stable")]
    cut = np.linspace(0, len(mine), shards + 1).round().astype(int)  # slabs: neighbours share their corners
    mine = mine.iloc[cut[shard]:cut[shard + 1]]
    for b in range(0, max(len(mine), 1), BATCH_VOXELS):
        yield _refine_batch(mine.iloc[b:b + BATCH_VOXELS], grid, problem, settings, rng, log, (b, len(mine)))


def _refine_batch(mine: pd.DataFrame, grid: Grid, problem: CapacityProblem, settings: RefineSettings,
                  rng: np.random.Generator, log, where: tuple[int, int]) -> RefinedBatch:
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
    return RefinedBatch(df, _configuration_table(res, grid, list(labels.names), names), res.rounds, res.n_evaluated,
                        start.capacity_kg)


def _configuration_table(res: VoxelMinima, grid: Grid, configurations: list[str], limit_names: list[str]) -> pd.DataFrame:
    """One row per voxel x configuration held by some evaluated point of the voxel."""
    v, c = np.nonzero(np.isfinite(res.config_capacity_kg))
    i, j, k = np.unravel_index(res.voxel[v], grid.shape)
    centre = grid.centres(np.stack([i, j, k], axis=1)) if len(v) else np.zeros((0, 3))
    w = res.config_worst_m[v, c]
    b = res.config_binding[v, c]
    df = pd.DataFrame({"i": i, "j": j, "k": k, "x_m": centre[:, 0], "y_m": centre[:, 1], "z_m": centre[:, 2],
                       "configuration": pd.Categorical.from_codes(c, configurations),
                       "capacity_kg": res.config_capacity_kg[v, c],
                       "binding": pd.Categorical.from_codes(np.where(b < 0, len(limit_names), b), limit_names + [""]),
                       "n_points": res.config_n_points[v, c], "converged": res.converged[v],
                       "worst_x_m": w[:, 0], "worst_y_m": w[:, 1], "worst_z_m": w[:, 2]})
    for a, col in enumerate(AXIS_COLUMNS):
        df[col] = res.config_axis_capacity_kg[v, c, a]
    return df[CONFIGURATION_COLUMNS]


def merge_refined(vox: pd.DataFrame, refined: list[pd.DataFrame]) -> pd.DataFrame:
    """The sampled voxel table ``vox`` with each refined voxel's values (``capacity_sampled_kg`` keeps the
    sampled minimum; no refined shards: the sampled table as is)."""
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
    return vox


def configuration_rows(chunks: Iterable[pd.DataFrame], grid: Grid, names: list[str]) -> Iterator[pd.DataFrame]:
    """The per-configuration rows of the refine shards (``chunks``: each shard's rows, chunk by chunk, the
    shards in order) as the map stores them, one chunk at a time: in (i, j, k, configuration) order (the
    shards are consecutive slabs of the grid's flat order, each in that order; checked), the
    configurations ``names`` as categories, the axis capacities as stored (:func:`axes_stored`). No chunk:
    one empty table."""
    last, binding = -1, None
    for df in chunks:
        if not len(df):
            continue
        if list(df.configuration.cat.categories) != list(names) or (
                binding is not None and list(df.binding.cat.categories) != binding):
            raise CapmapError("the refine shards disagree on the configurations or limits: rerun `refine`")
        binding = list(df.binding.cat.categories)
        key = grid.flat(df[["i", "j", "k"]].to_numpy()) * len(names) + df.configuration.cat.codes.to_numpy()
        if key[0] <= last or np.any(np.diff(key) <= 0):
            raise CapmapError("the refine shards' configuration rows are not in (i, j, k, configuration) order")
        last = int(key[-1])
        yield axes_stored(df)[CONFIGURATION_COLUMNS]
    if last < 0:
        yield pd.DataFrame({c: [] for c in CONFIGURATION_COLUMNS})
