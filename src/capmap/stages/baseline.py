"""Stages of the healthy-arm baseline (:mod:`capmap.capacity.baseline`): baseline_shard (shard k of n
of the healthy arm's voxels on the map's lattice, each voxel's minimum refined as the map's) ->
baseline_map (the healthy map beside the failed one: the loss per voxel, the angle step's
convergence, the summary and the figure)."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from capmap.capacity import sampling
from capmap.capacity.baseline import SelfMotion, healthy_capacity, screening_subset, self_motion_angles
from capmap.capacity.engine import argmin_per_group
from capmap.capacity.refine import Evaluation, VoxelMinima, refine
from capmap.capacity.tables import configuration_voxels, grid_of
from capmap.capacity.voxels import Grid
from capmap.config.failure import locked_arm
from capmap.core.reduction import free
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_quantities
from capmap.stages.arm import ArmTask, arm_task_from, configuration_name
from capmap.stages.common import stage_config

__all__ = ["HEALTHY_COLUMNS", "BASELINE_COLUMNS", "stage_baseline_shard", "stage_baseline_map", "self_motion_of",
           "healthy_samples"]

HEALTHY_COLUMNS = ["x_m", "y_m", "z_m", "healthy_capacity_kg", "healthy_binding", "healthy_angle_deg", "n_points",
                   "n_reachable", "converged", "last_change_rel", "worst_x_m", "worst_y_m", "worst_z_m"]
# baseline/voxels.parquet: the healthy map on the failed map's grid (i, j, k may fall outside its box), the
# failed map's values (all branches; the arm's configuration) and the loss, healthy - failed (failed: 0 kg
# where it reaches no point of the voxel)
BASELINE_COLUMNS = ["i", "j", "k", *HEALTHY_COLUMNS[:6], "n_points", "converged", "capacity_kg",
                    "arm_configuration_capacity_kg", "loss_kg", "arm_configuration_loss_kg"]
_CHUNK = 1000  # points per call of the evaluation (memory: ~36 angles x 8 solutions each)


def self_motion_of(at: ArmTask, run, step_deg: float) -> SelfMotion:
    """The failed joint's angles (through the failed angle, ``step_deg`` apart) and the arm held at each."""
    robot, j = at.robot, run.failure.joint
    lo, hi = np.rad2deg(robot.q_lower[j - 1]), np.rad2deg(robot.q_upper[j - 1])
    limits = run.limits.resolve(robot.n_joints)
    return SelfMotion.build(self_motion_angles(lo, hi, run.failure.angle_deg, step_deg),
                            lambda a: locked_arm(robot, j, a), limits.for_arm)


def healthy_samples(at: ArmTask, run) -> tuple[np.ndarray, Grid]:
    """The healthy arm's Monte Carlo positions (every joint moving; the run's sampling: seed, points,
    and for voxel_fill every voxel of their box) and the grid covering them, on the map's lattice
    (anchored at multiples of the edge, as every map's grid)."""
    sc = run.sampling
    rng = np.random.default_rng(sc.seed)
    _, pos = sampling.joint_samples(free(at.robot), sc.n_points, rng)
    grid = Grid.covering(pos, run.voxel_edge_m)
    if sc.mode == "voxel_fill":
        pos = np.concatenate([pos, sampling.voxel_fill(grid, sc.jitter_per_voxel, rng)[0]])
    return pos, grid


def _lattice_union(a: Grid, b: Grid) -> Grid:
    """The grid on the same lattice covering both grids."""
    lo = np.minimum(a.lower, b.lower)
    hi = np.maximum(a.lower + np.array(a.shape) * a.edge_m, b.lower + np.array(b.shape) * b.edge_m)
    return Grid(lower=lo, shape=tuple(int(n) for n in np.rint((hi - lo) / a.edge_m)), edge_m=a.edge_m)


def stage_baseline_shard(voxels: str, out: str, slice_json: str, shard: int, shards: int) -> None:
    """The healthy arm's voxels with flat index % shards == shard: its sampled points there and the
    failed map's worst point of the voxel, then each voxel's minimum refined as the map's (the run's
    ``voxels.refine``); one row per voxel that a point reaches."""
    cfg = stage_config(slice_json)
    run, bl = cfg.run, cfg.run.baseline
    log = stage_logger(__name__, f"baseline shard {shard} of {shards}")
    at = arm_task_from(run)
    sm = self_motion_of(at, run, bl.step_deg)
    dirs = run.directions.build()
    screen = screening_subset(dirs, bl.screen_directions)
    failed = datasets.read(voxels)
    fg = grid_of(failed)
    fr = failed[(failed.n_reachable > 0) & failed.worst_x_m.notna()]
    pos, grid = healthy_samples(at, run)
    grid = _lattice_union(grid, fg)
    flat = grid.flat(grid.index(pos))
    # the failed map's worst points, each in its own voxel (one on a face belongs to the voxel it was refined in)
    shift = np.rint((fg.lower - grid.lower) / grid.edge_m).astype(int)
    pos = np.concatenate([pos, fr[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy()])
    flat = np.concatenate([flat, grid.flat(fr[["i", "j", "k"]].to_numpy() + shift)])
    mine = flat % shards == shard
    pos, flat = pos[mine], flat[mine]
    t0, done = time.perf_counter(), [0]

    hint_of = np.full(grid.n_voxels, -1)  # per voxel: the angle (index) of its least value's posture

    def evaluate(points: np.ndarray, ceiling: np.ndarray | None = None, owner: np.ndarray | None = None
                 ) -> Evaluation:
        """Each voxel's least value exact (the others may stop at it: tried first at the angle of the
        voxel's least value so far), a voxel's points evaluated together."""
        order = np.argsort(owner, kind="stable") if owner is not None else np.arange(len(points))
        cap, binding, angle = np.full(len(points), np.nan), np.full(len(points), -1), np.full(len(points), np.nan)
        for r in range(0, len(points), _CHUNK):
            rows = order[r:r + _CHUNK]
            hc = healthy_capacity(sm, points[rows], at.rotation, dirs, screen, at.motion,
                                  None if ceiling is None else ceiling[rows], None if owner is None else owner[rows],
                                  None if owner is None else hint_of[owner[rows]])
            cap[rows], binding[rows], angle[rows] = hc.capacity_kg, hc.binding, hc.angle_deg
            done[0] += len(rows)
        if owner is not None and len(points):  # a voxel's new least value: its angle is the voxel's next hint
            c = np.where(np.isfinite(cap), cap, np.inf)
            i = argmin_per_group(c, owner)
            new = np.isfinite(c[i]) & (c[i] < (np.inf if ceiling is None else ceiling[i]))
            hint_of[owner[i[new]]] = np.searchsorted(sm.angles_deg, angle[i[new]])
        return Evaluation(cap, np.zeros((len(cap), 0)), binding, np.isfinite(cap).astype(int))

    # the first point of each voxel exactly, then the others against it (only a lower value needs to be exact)
    first = np.zeros(len(flat), dtype=bool)
    first[np.unique(flat, return_index=True)[1]] = True
    ev1 = evaluate(pos[first], None, flat[first])
    head = np.full(grid.n_voxels, np.inf)
    head[flat[first]] = np.where(np.isfinite(ev1.capacity_kg), ev1.capacity_kg, np.inf)
    ev2 = evaluate(pos[~first], head[flat[~first]], flat[~first])
    vox_of = np.unique(flat)
    log.info(f"{len(vox_of)} voxels, {len(pos)} sampled points over {len(sm.angles_deg)} angles of joint "
             f"{run.failure.joint} ({time.perf_counter() - t0:.1f} s)")
    cap, binding = np.full(len(pos), np.nan), np.full(len(pos), -1)
    cap[first], cap[~first] = ev1.capacity_kg, ev2.capacity_kg
    binding[first], binding[~first] = ev1.binding, ev2.binding
    start = _start(grid, vox_of, flat, pos, cap, binding)
    settings = run.refine.settings(sorted(run.task.payload_kg)) if run.refine is not None else None
    res = start
    if settings is not None:
        def progress(rnd: int, active: int, points: int) -> None:
            log.info(f"round {rnd}: {active} of {len(vox_of)} voxels not converged, {points} new points "
                     f"({time.perf_counter() - t0:.1f} s so far)")

        res = refine(grid, start, evaluate, settings, np.random.default_rng([run.refine.seed, shard, shards, 7]),
                     progress, share_points=False)  # its evaluate prunes a point by its voxel's other points
    reach = np.isfinite(res.capacity_kg)
    final = healthy_capacity(sm, res.worst_m[reach], at.rotation, dirs, screen, at.motion)  # exact, with its angle
    names = list(sm.limits.names) + ["singular"]
    off = final.capacity_kg - res.capacity_kg[reach]  # > 0 only where a tie kept a point stopped at its ceiling
    if len(off) and np.nanmax(np.abs(off)) > 1e-9 * max(1.0, np.nanmax(np.abs(final.capacity_kg))):
        log.info(f"worst points re-evaluated: {np.nanmax(np.abs(off)):.3g} kg from the voxel minimum at most (ties)")
    centres = grid.centres(np.stack(np.unravel_index(res.voxel[reach], grid.shape), axis=1))
    df = pd.DataFrame({"x_m": centres[:, 0], "y_m": centres[:, 1], "z_m": centres[:, 2],
                       "healthy_capacity_kg": res.capacity_kg[reach],
                       "healthy_binding": pd.Categorical(np.array(names)[final.binding]),
                       "healthy_angle_deg": final.angle_deg, "n_points": res.n_points[reach],
                       "n_reachable": res.n_reachable[reach], "converged": res.converged[reach],
                       "last_change_rel": res.last_change[reach], "worst_x_m": res.worst_m[reach, 0],
                       "worst_y_m": res.worst_m[reach, 1], "worst_z_m": res.worst_m[reach, 2]})
    seconds = time.perf_counter() - t0
    datasets.write(df[HEALTHY_COLUMNS], out, datasets.provenance(
        "baseline", cfg.doc, shard=shard, shards=shards, angles_deg=sm.angles_deg.tolist(), seconds=seconds,
        points_evaluated=done[0], screen_directions=len(screen)))
    log.info(f"done: {len(df)} voxels, {done[0]} points evaluated ({done[0] / max(len(df), 1):.1f} per voxel), "
             f"{int((~df.converged).sum()) if settings else len(df)} not converged, {seconds:.1f} s -> {out}")


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


def stage_baseline_map(shards: list[str], voxels: str, configurations: str, out: str, out_convergence: str,
                       out_csv: str, out_md: str, slice_json: str) -> None:
    """The healthy map beside the failed one (``out``), the angle step's convergence at the worst points
    of ``baseline.check_voxels`` voxels (``out_convergence``) and the summary (CSV + Markdown)."""
    cfg = stage_config(slice_json)
    run, bl = cfg.run, cfg.run.baseline
    log = stage_logger(__name__, "baseline map")
    parts = [datasets.read(p) for p in shards]
    h = pd.concat(parts, ignore_index=True)
    failed = datasets.read(voxels)
    grid = grid_of(failed)
    name = configuration_name(run, run.failure.q_start_deg)
    op = configuration_voxels(failed, datasets.read(configurations), name)
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
    df = df.sort_values(["i", "j", "k"], ignore_index=True)
    meta = parts[0].attrs["capmap"]
    cost_s = sum(p.attrs["capmap"]["seconds"] for p in parts)
    t0 = time.perf_counter()
    conv = _convergence(run, bl, h, np.random.default_rng(run.sampling.seed))
    cost_s += time.perf_counter() - t0
    datasets.write(df[BASELINE_COLUMNS], out, datasets.provenance(
        "baseline", cfg.doc, grid=failed.attrs["capmap"]["grid"], configuration=name, angles_deg=meta["angles_deg"],
        core_seconds=cost_s, points_evaluated=sum(p.attrs["capmap"]["points_evaluated"] for p in parts)))
    datasets.write(conv, out_convergence, datasets.provenance("baseline", cfg.doc, step_deg=bl.step_deg))
    write_quantities(_summary(run, df, conv, name, len(meta["angles_deg"]), cost_s, op is not None), out_csv, out_md)
    log.info(f"{int(df.healthy_capacity_kg.notna().sum())} healthy voxels, {int(df.capacity_kg.notna().sum())} "
             f"failed; median loss {df.loss_kg.median():.1f} kg; {cost_s:.0f} core-s -> {out}")


def _convergence(run, bl, h: pd.DataFrame, rng: np.random.Generator) -> pd.DataFrame:
    """The healthy value at the worst points of ``bl.check_voxels`` voxels with the angle step, half and a
    quarter of it: each voxel's value can rise by at most its worst point's rise (a finer grid holds
    the coarser one's angles), so the table bounds the change of the map."""
    at = arm_task_from(run)
    dirs = run.directions.build()
    screen = screening_subset(dirs, bl.screen_directions)
    rows = h[h.healthy_capacity_kg.notna()]
    rows = rows.iloc[np.sort(rng.choice(len(rows), size=min(bl.check_voxels, len(rows)), replace=False))]
    pts = rows[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy()
    out = pd.DataFrame({"x_m": pts[:, 0], "y_m": pts[:, 1], "z_m": pts[:, 2]})
    for col, div in (("healthy_capacity_kg", 1), ("healthy_half_step_kg", 2), ("healthy_quarter_step_kg", 4)):
        sm = self_motion_of(at, run, bl.step_deg / div)
        out[col] = healthy_capacity(sm, pts, at.rotation, dirs, screen, at.motion).capacity_kg
    base = out.healthy_capacity_kg.where(out.healthy_capacity_kg > 0)
    out["rise_half_step_rel"] = (out.healthy_half_step_kg - out.healthy_capacity_kg) / base
    out["rise_quarter_step_rel"] = (out.healthy_quarter_step_kg - out.healthy_capacity_kg) / base
    return out


def _summary(run, df: pd.DataFrame, conv: pd.DataFrame, name: str, n_angles: int, cost_s: float,
             configurations: bool) -> list[tuple[str, object]]:
    j, bl = run.failure.joint, run.baseline
    healthy = df.healthy_capacity_kg
    rows = [(f"failed joint {j}, locked at [deg]", run.failure.angle_deg),
            (f"joint {j} angles swept (healthy arm), step [deg]", f"{n_angles}, {bl.step_deg:g}"),
            ("voxels the healthy arm reaches", int(healthy.notna().sum())),
            ("voxels the failed arm reaches (any configuration)", int(df.capacity_kg.notna().sum())),
            (f"voxels the failed arm reaches on its configuration {name}", int(df.arm_configuration_capacity_kg.notna().sum()))]
    for m in sorted(run.task.payload_kg):
        rows += [(f"voxels carrying {m:g} kg: healthy", int((healthy >= m).sum())),
                 (f"voxels carrying {m:g} kg: failed, any configuration", int((df.capacity_kg >= m).sum()))]
        if configurations:
            rows.append((f"voxels carrying {m:g} kg: failed, on {name}", int((df.arm_configuration_capacity_kg >= m).sum())))
    has = healthy.notna()
    rows += [("loss median, any configuration [kg]", round(float(df.loss_kg[has].median()), 1)),
             ("loss max, any configuration [kg]", round(float(df.loss_kg[has].max()), 1))]
    if configurations:
        rows += [(f"loss median, on {name} [kg]", round(float(df.arm_configuration_loss_kg[has].median()), 1)),
                 (f"loss max, on {name} [kg]", round(float(df.arm_configuration_loss_kg[has].max()), 1))]
    below = has & df.capacity_kg.notna() & (df.loss_kg < 0)
    rows += [("voxels where the healthy value is below the failed one (minima over different parts of the voxel)",
              int(below.sum())),
             ("healthy voxels not converged", int((has & ~df.converged.fillna(False).astype(bool)).sum())),
             (f"angle step check: largest rise at {bl.step_deg / 2:g} deg [%]",
              round(100 * float(conv.rise_half_step_rel.max()), 3) if len(conv) else np.nan),
             (f"angle step check: largest rise at {bl.step_deg / 4:g} deg [%]",
              round(100 * float(conv.rise_quarter_step_rel.max()), 3) if len(conv) else np.nan),
             ("angle step check: voxels", len(conv)),
             ("cost [core-s]", round(cost_s, 1))]
    return rows
