"""The healthy arm's map beside the failed one (:mod:`capmap.capacity.baseline` for the healthy value):
one shard of the healthy arm's voxels on the failed map's lattice, refined as the map's
(:class:`~capmap.capacity.healthy_evaluator.HealthyEvaluator`), the angle step's convergence at sampled
voxels' worst points, and the family's column schemas of these tables. No file I/O."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from capmap.capacity import sampling
from capmap.capacity.baseline import healthy_capacity
from capmap.capacity.healthy_evaluator import HealthyEvaluator
from capmap.capacity.refine import RefineSettings, VoxelMinima, refine
from capmap.capacity.self_motion import HealthyProblem
from capmap.capacity.tables import grid_of
from capmap.capacity.voxels import Grid
from capmap.core.parallel import by_rows
from capmap.core.reduction import free

__all__ = ["HEALTHY_COLUMNS", "BASELINE_COLUMNS", "healthy_samples", "baseline_shard", "loss_table",
           "angle_convergence", "CONVERGENCE_COLUMNS"]

HEALTHY_COLUMNS = ["x_m", "y_m", "z_m", "healthy_capacity_kg", "healthy_binding", "healthy_angle_deg", "n_points",
                   "n_reachable", "converged", "last_change_rel", "worst_x_m", "worst_y_m", "worst_z_m"]
# baseline/voxels.parquet: the healthy map on the failed map's grid (i, j, k may fall outside its box), the
# failed map's values (all branches; the arm's configuration) and the loss, healthy - failed (failed: 0 kg
# where it reaches no point of the voxel)
BASELINE_COLUMNS = ["i", "j", "k", *HEALTHY_COLUMNS[:6], "n_points", "converged", "capacity_kg",
                    "arm_configuration_capacity_kg", "loss_kg", "arm_configuration_loss_kg"]
# baseline/convergence.parquet: the check of the angle search at sampled voxels' worst points
CONVERGENCE_COLUMNS = ["x_m", "y_m", "z_m", "healthy_capacity_kg", "healthy_reference_kg", "shortfall_rel"]
_CHUNK = 500  # points per call of the evaluation (memory: ~36 angles x 8 solutions each, their coefficients kept)


def healthy_samples(robot, sc, edge_m: float) -> tuple[np.ndarray, Grid]:
    """The healthy arm's Monte Carlo positions (every joint of ``robot`` moving; the run's sampling
    ``sc``: seed, points, and for voxel_fill every voxel of their box) and the grid of ``edge_m`` [m]
    covering them, on the map's lattice (anchored at multiples of the edge, as every map's grid)."""
    rng = np.random.default_rng(sc.seed)
    _, pos = sampling.joint_samples(free(robot), sc.n_points, rng)
    grid = Grid.covering(pos, edge_m)
    if sc.mode == "voxel_fill":
        pos = np.concatenate([pos, sampling.voxel_fill(grid, sc.jitter_per_voxel, rng)[0]])
    return pos, grid


def _lattice_union(a: Grid, b: Grid) -> Grid:
    """The grid on the same lattice covering both grids."""
    lo = np.minimum(a.lower, b.lower)
    hi = np.maximum(a.lower + np.array(a.shape) * a.edge_m, b.lower + np.array(b.shape) * b.edge_m)
    return Grid(lower=lo, shape=tuple(int(n) for n in np.rint((hi - lo) / a.edge_m)), edge_m=a.edge_m)


def baseline_shard(hp: HealthyProblem, failed: pd.DataFrame, samples: tuple[np.ndarray, Grid],
                   settings: RefineSettings | None, part: tuple[int, int], rng: np.random.Generator,
                   log) -> tuple[pd.DataFrame, dict]:
    """Shard ``part`` = (k, n) of the healthy arm: its voxels with flat index % n == k, its sampled points there (``samples``:
    positions and their grid, :func:`healthy_samples`) and the failed map's worst point of each voxel,
    then each voxel's minimum refined as the map's (``settings``; None: not refined). One row per voxel
    that a point reaches (:data:`HEALTHY_COLUMNS`) and the provenance fields (angles, seconds, points)."""
    t0 = time.perf_counter()
    fg = grid_of(failed)
    fr = failed[(failed.n_reachable > 0) & failed.worst_x_m.notna()]
    grid = _lattice_union(samples[1], fg)
    # the failed map's worst points, each in its own voxel (one on a face belongs to the voxel it was refined in), first:
    # a voxel's first point is searched in full and the others against it, and the failed arm's worst point is often
    # the healthy arm's too (measured: 14 % less time than with a sample first; the values are the same)
    shift = np.rint((fg.lower - grid.lower) / grid.edge_m).astype(int)
    pos = np.concatenate([fr[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy(), samples[0]])
    flat = np.concatenate([grid.flat(fr[["i", "j", "k"]].to_numpy() + shift), grid.flat(grid.index(samples[0]))])
    shard, shards = part
    mine = flat % shards == shard
    pos, flat = pos[mine], flat[mine]
    vox_of, first_of, row = np.unique(flat, return_index=True, return_inverse=True)
    row = row.reshape(-1)  # each point's voxel, as the refinement numbers them: its row in vox_of
    ev = HealthyEvaluator(hp, len(vox_of), _CHUNK)
    # the first point of each voxel exactly, then the others against it (only a lower value needs to be exact)
    first = np.zeros(len(flat), dtype=bool)
    first[first_of] = True
    ev1 = ev.evaluate(pos[first], None, row[first])
    head = np.full(len(vox_of), np.inf)
    head[row[first]] = np.where(np.isfinite(ev1.capacity_kg), ev1.capacity_kg, np.inf)
    ev2 = ev.evaluate(pos[~first], head[row[~first]], row[~first])
    log.info(f"{len(vox_of)} voxels, {len(pos)} sampled points over {len(hp.sm.angles_deg)} angles of joint "
             f"{hp.problem.arm.locked_joint} ({time.perf_counter() - t0:.1f} s)")
    cap, binding = np.full(len(pos), np.nan), np.full(len(pos), -1)
    cap[first], cap[~first] = ev1.capacity_kg, ev2.capacity_kg
    binding[first], binding[~first] = ev1.binding, ev2.binding
    res = _start(grid, vox_of, flat, pos, cap, binding)
    if settings is not None:
        def progress(rnd: int, active: int, points: int) -> None:
            log.info(f"round {rnd}: {active} of {len(vox_of)} voxels not converged, {points} new points "
                     f"({time.perf_counter() - t0:.1f} s so far)")

        res = refine(grid, res, ev, settings, rng, progress)
    return _healthy_table(hp, grid, res, ev, log), {
        "angles_deg": hp.sm.angles_deg.tolist(), "seconds": time.perf_counter() - t0,
        "points_evaluated": ev.n_evaluated, "screen_directions": len(hp.screen)}


def _healthy_table(hp: HealthyProblem, grid: Grid, res: VoxelMinima, ev: HealthyEvaluator, log
                   ) -> pd.DataFrame:
    """One row per reached voxel (:data:`HEALTHY_COLUMNS`), with the angle of its minimum's posture: the one the
    evaluator ``ev`` kept for the voxel (per row) where its point is the voxel's worst; elsewhere (a tie
    between points: the refinement kept another) the worst point searched again for a posture reaching the
    voxel's value, from the voxel's hint (its binding limit then that posture's)."""
    reach = np.isfinite(res.capacity_kg)
    angle, binding = ev.angle_of[reach], res.binding[reach].copy()
    again = ~np.all(ev.least_m[reach] == res.worst_m[reach], axis=1) | np.isnan(angle)
    if again.any():
        hint = ev.hint(np.flatnonzero(reach)[again])
        final = healthy_capacity(hp, res.worst_m[reach][again], res.capacity_kg[reach][again], hint=hint)
        angle[again], binding[again] = final.angle_deg, final.binding
        log.info(f"{int(again.sum())} worst points searched again for their angle (ties)")
    names = list(hp.sm.limits.names) + ["singular"]
    centres = grid.centres(np.stack(np.unravel_index(res.voxel[reach], grid.shape), axis=1))
    return pd.DataFrame({"x_m": centres[:, 0], "y_m": centres[:, 1], "z_m": centres[:, 2],
                         "healthy_capacity_kg": res.capacity_kg[reach],
                         "healthy_binding": pd.Categorical(np.array(names)[binding]),
                         "healthy_angle_deg": angle, "n_points": res.n_points[reach],
                         "n_reachable": res.n_reachable[reach], "converged": res.converged[reach],
                         "last_change_rel": res.last_change[reach], "worst_x_m": res.worst_m[reach, 0],
                         "worst_y_m": res.worst_m[reach, 1], "worst_z_m": res.worst_m[reach, 2]})[HEALTHY_COLUMNS]


def _start(grid: Grid, vox_of: np.ndarray, flat: np.ndarray, pos: np.ndarray, cap: np.ndarray,
           binding: np.ndarray) -> VoxelMinima:
    """The voxels' minima over their evaluated points (the refinement's start)."""
    V = len(vox_of)
    row = np.searchsorted(vox_of, flat)
    n_pts = np.bincount(row, minlength=V)
    reach = np.isfinite(cap)
    n_reach = np.bincount(row[reach], minlength=V)
    low = np.full(V, np.inf)
    np.minimum.at(low, row[reach], cap[reach])
    worst = np.full((V, 3), np.nan)
    wb = np.full(V, -1)
    at_min = reach & (cap == low[row])
    worst[row[at_min]], wb[row[at_min]] = pos[at_min], binding[at_min]
    low[n_reach == 0] = np.nan
    return VoxelMinima(voxel=vox_of, capacity_kg=low, axis_capacity_kg=np.zeros((V, 0)), n_points=n_pts,
                       n_reachable=n_reach, last_change=np.zeros(V), converged=np.zeros(V, dtype=bool), worst_m=worst,
                       binding=wb, rounds=0, n_evaluated=0)


def loss_table(h: pd.DataFrame, failed: pd.DataFrame, op: pd.DataFrame | None) -> pd.DataFrame:
    """The healthy map ``h`` (the shards' rows) beside the failed one (``failed``: its voxel table; ``op``: its
    voxels on the arm's configuration, None without configuration maps) on the failed map's grid, one row
    per voxel either reaches, sorted by (i, j, k): the loss, healthy - failed (failed: 0 kg where it reaches
    no point of the voxel), of all branches and of the arm's configuration."""
    grid = grid_of(failed)
    h = h.copy()
    h[["i", "j", "k"]] = np.rint((h[["x_m", "y_m", "z_m"]].to_numpy() - grid.lower) / grid.edge_m - 0.5).astype(int)
    f = failed.loc[failed.n_reachable > 0, ["i", "j", "k", "capacity_kg"]]
    if op is not None:
        f = f.merge(op.loc[op.n_reachable > 0, ["i", "j", "k", "capacity_kg"]].rename(
            columns={"capacity_kg": "arm_configuration_capacity_kg"}), on=["i", "j", "k"], how="left")
    else:
        f["arm_configuration_capacity_kg"] = np.nan
    df = h.drop(columns=["n_reachable", "last_change_rel"]).merge(f, on=["i", "j", "k"], how="outer")
    idx = df[["i", "j", "k"]].to_numpy()
    df[["x_m", "y_m", "z_m"]] = grid.lower + (idx + 0.5) * grid.edge_m
    df["loss_kg"] = df.healthy_capacity_kg - df.capacity_kg.fillna(0.0)
    df["arm_configuration_loss_kg"] = (df.healthy_capacity_kg - df.arm_configuration_capacity_kg.fillna(0.0)
                                       if op is not None else np.nan)
    return df.sort_values(["i", "j", "k"], ignore_index=True)


def angle_convergence(hp: HealthyProblem, reference: HealthyProblem, h: pd.DataFrame, n_voxels: int,
                      rng: np.random.Generator, workers: int = 1) -> pd.DataFrame:
    """The healthy value at the worst points of ``n_voxels`` random voxels of the healthy table ``h``, by
    the map's search ``hp`` and by the finer grid ``reference`` (every angle of it, not followed):
    ``shortfall_rel`` = (reference - map) / reference, > 0 where the map's value lies below the finer
    sweep's (both are postures' values: lower bounds of the healthy arm's); 0 where both are 0 kg. Each
    point's values are its own (no ceiling, no group), so the points split over ``workers`` processes."""
    rows = h[h.healthy_capacity_kg.notna()]
    rows = rows.iloc[np.sort(rng.choice(len(rows), size=min(n_voxels, len(rows)), replace=False))]
    pts = rows[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy()
    out = pd.DataFrame({"x_m": pts[:, 0], "y_m": pts[:, 1], "z_m": pts[:, 2]})
    both = by_rows(lambda p: np.stack([healthy_capacity(hp, p).capacity_kg, healthy_capacity(reference, p).capacity_kg],
                                      axis=1), pts, workers)
    out["healthy_capacity_kg"], out["healthy_reference_kg"] = both[:, 0], both[:, 1]
    ref, got = out.healthy_reference_kg.to_numpy(), out.healthy_capacity_kg.to_numpy()
    with np.errstate(invalid="ignore", divide="ignore"):
        out["shortfall_rel"] = np.where(ref > 0, (ref - got) / ref, np.where(got >= ref, 0.0, np.nan))
    return out
