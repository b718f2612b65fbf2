"""Pipeline stages: one function per Snakemake rule (file I/O and logging live here).

Each function takes its inputs/outputs as paths and ``slice_json``: the canonical JSON
of the config slice it depends on (see :func:`capmap.config.stage_slices`), which is
also recorded as the outputs' provenance. Numerics are delegated to the stage modules.
"""

from __future__ import annotations

import json
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pandas as pd

from capmap import capacity as cap_mod
from capmap import datasets, ik, planning, sampling, trajectory, verification
from capmap.config import (
    DirectionsConfig,
    LimitsConfig,
    LockConfig,
    SamplingConfig,
    TaskConfig,
    per_item,
)
from capmap.dynamics import ArmDynamics, output_names
from capmap.errors import CapmapError
from capmap.locking import LockedArm, lock
from capmap.robot import Robot, load
from capmap.voxels import Grid, voxelise


class Log:
    """Progress lines to a log file and stderr (a person may be waiting)."""

    def __init__(self, path: str | Path | None, prefix: str):
        self.prefix = prefix
        self.file = open(path, "a") if path else None

    def __call__(self, msg: str) -> None:
        line = f"[{time.strftime('%H:%M:%S')}] {self.prefix}: {msg}"
        print(line, file=sys.stderr, flush=True)
        if self.file:
            self.file.write(line + "\n")
            self.file.flush()


@contextmanager
def one_line_errors(log_path: str | Path | None = None):
    """Turn a CapmapError into one line on stderr (and the log) and exit status 1."""
    try:
        yield
    except CapmapError as exc:
        msg = f"capmap: {exc}"
        print(msg, file=sys.stderr)
        if log_path:
            with open(log_path, "a") as f:
                f.write(msg + "\n")
        raise SystemExit(1) from None


def _arm_from(sl: dict) -> tuple[Robot, LockedArm]:
    robot = load(sl["model"]["robot"])
    lk = LockConfig(**sl["sample"]["lock"])
    return robot, lock(robot, lk.joint, np.deg2rad(lk.angle_deg))


# --------------------------------------------------------------------------- model


def model_table(robot: Robot) -> pd.DataFrame:
    """Joint/link table of a built robot (angles in deg)."""
    import pinocchio as pin

    m = robot.model
    rows = []
    for j in range(1, m.njoints):
        inertia = m.inertias[j]
        I = inertia.inertia
        M = m.jointPlacements[j]
        rpy = np.rad2deg(pin.rpy.matrixToRpy(M.rotation))
        rows.append({
            "joint": j, "name": m.names[j], "type": m.joints[j].shortname(),
            "lower_deg": np.rad2deg(robot.q_lower[j - 1]), "upper_deg": np.rad2deg(robot.q_upper[j - 1]),
            "placement_x_m": M.translation[0], "placement_y_m": M.translation[1], "placement_z_m": M.translation[2],
            "placement_roll_deg": rpy[0], "placement_pitch_deg": rpy[1], "placement_yaw_deg": rpy[2],
            "mass_kg": inertia.mass, "com_x_m": inertia.lever[0], "com_y_m": inertia.lever[1], "com_z_m": inertia.lever[2],
            "ixx_kgm2": I[0, 0], "iyy_kgm2": I[1, 1], "izz_kgm2": I[2, 2], "ixy_kgm2": I[0, 1], "ixz_kgm2": I[0, 2],
            "iyz_kgm2": I[1, 2],
        })
    return pd.DataFrame(rows)


def stage_model(robot_yaml: str, out: str, slice_json: str, log: str | None = None) -> None:
    sl = json.loads(slice_json)
    robot = load(robot_yaml)
    df = model_table(robot)
    datasets.write(df, out, datasets.provenance("model", sl, robot=robot.name,
                                                 gravity_mps2=robot.gravity.tolist(), base_com_m=robot.base_com.tolist()))
    Log(log, "model")(f"{robot.name}: {robot.n_joints} joints, total mass {df.mass_kg.sum():.1f} kg -> {out}")


# --------------------------------------------------------------------------- sample


def stage_sample(out: str, slice_json: str, log: str | None = None) -> None:
    sl = json.loads(slice_json)
    lg = Log(log, "sample")
    _, arm = _arm_from(sl)
    sc = SamplingConfig(**sl["sample"]["sampling"])
    rng = np.random.default_rng(sc.seed)
    q, pos = sampling.joint_samples(arm, sc.n_points, rng)
    source = np.zeros(len(pos), dtype=int)
    if sc.mode == "voxel_fill":
        grid = Grid.covering(pos, sl["sample"]["voxels"]["edge_m"])
        fill, kind = sampling.voxel_fill(grid, sc.jitter_per_voxel, rng)
        pos = np.concatenate([pos, fill])
        source = np.concatenate([source, kind + 1])
        lg(f"voxel_fill: grid {grid.shape} of {grid.edge_m} m = {grid.n_voxels} voxels, "
           f"+{len(fill)} points (centre + {sc.jitter_per_voxel} jittered each)")
    df = pd.DataFrame({"point_id": np.arange(len(pos)), "x_m": pos[:, 0], "y_m": pos[:, 1], "z_m": pos[:, 2],
                       "source": pd.Categorical.from_codes(source, ["joint_sample", "voxel_centre", "voxel_jitter"])})
    datasets.write(df, out, datasets.provenance("sample", sl, seed=sc.seed))
    lg(f"{len(df)} points ({sc.n_points} joint samples, mode {sc.mode}, seed {sc.seed}) -> {out}")


# --------------------------------------------------------------------------- capacity


def capacity_table(arm: LockedArm, ids: np.ndarray, pos: np.ndarray, rotation: np.ndarray, motion: cap_mod.Motion,
                   limits: cap_mod.Limits, dirs, log=None, chunk: int = 500) -> pd.DataFrame:
    """Per-point capacity table for points ``pos`` (N, 3) m at end-effector orientation ``rotation``
    (all IK branches x all directions)."""
    dyn = ArmDynamics(arm)
    parts = []
    t0, states = time.perf_counter(), 0
    for start in range(0, len(pos), chunk):
        sl = slice(start, start + chunk)
        sol = ik.solve(arm, pos[sl], rotation)
        pc = cap_mod.point_capacity(dyn, sol.q, sol.n_solutions, dirs, motion, limits)
        states += int(pc.n_states.sum())
        reach = sol.n_solutions > 0
        d = np.where(pc.direction >= 0, pc.direction, 0)
        br = np.where(pc.branch >= 0, pc.branch, 0)
        q_worst = np.where(reach[:, None], sol.q[np.arange(len(br)), br], np.nan)
        part = pd.DataFrame({
            "point_id": ids[sl], "x_m": pos[sl, 0], "y_m": pos[sl, 1], "z_m": pos[sl, 2],
            "reachable": reach, "n_branches": sol.n_solutions, "capacity_kg": pc.capacity_kg,
            "binding": np.where(reach, np.array(pc.names + ("",))[pc.binding], ""),
            "worst_branch": pc.branch,
            "worst_alpha_deg": np.where(reach, dirs.alpha_deg[d], np.nan),
            "worst_beta_deg": np.where(reach, dirs.beta_deg[d], np.nan),
            "worst_ux": np.where(reach, dirs.u[d, 0], np.nan), "worst_uy": np.where(reach, dirs.u[d, 1], np.nan),
            "worst_uz": np.where(reach, dirs.u[d, 2], np.nan),
            "n_states": pc.n_states,
        })
        for c, j in enumerate(arm.active_joint_numbers):
            part[f"worst_q_j{j}_deg"] = np.rad2deg(q_worst[:, c])
        parts.append(part)
        if log:
            done = min(start + chunk, len(pos))
            el = time.perf_counter() - t0
            log(f"{done}/{len(pos)} points ({done / len(pos):.0%}), {states / el:,.0f} states/s, "
                f"eta {el / done * (len(pos) - done):.0f} s")
    df = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()
    if len(df):
        df["binding"] = df["binding"].astype("category")
    return df


def stage_capacity(points: str, out: str, slice_json: str, shard: int, shards: int, log: str | None = None) -> None:
    """Shard ``shard`` (0-based) of ``shards``: points with point_id % shards == shard."""
    sl = json.loads(slice_json)
    lg = Log(log, f"capacity shard {shard + 1}/{shards}")
    robot, arm = _arm_from(sl)
    cs = sl["capacity"]
    task = cs["task"]
    rotation = TaskConfig.rotation_from_rpy(task["orientation_rpy_deg"])
    motion = cap_mod.Motion(task["v_max_mps"], task["a_max_mps2"])
    limits = LimitsConfig(**cs["limits"]).resolve(robot.n_joints)
    limits.vector(arm)  # validate before the long work
    dirs = DirectionsConfig(**cs["directions"]).build()
    pts = datasets.read(points)
    mine = pts[pts.point_id % shards == shard]
    lg(f"{len(mine)} of {len(pts)} points, {len(dirs)} directions ({dirs.kind})")
    df = capacity_table(arm, mine.point_id.to_numpy(), mine[["x_m", "y_m", "z_m"]].to_numpy(), rotation, motion,
                        limits, dirs, lg)
    datasets.write(df, out, datasets.provenance("capacity", sl, seed=sl["sample"]["sampling"]["seed"],
                                                 shard=shard, shards=shards, directions=dirs.kind))
    n_reach = int(df.reachable.sum()) if len(df) else 0
    lg(f"done: {n_reach} reachable, min capacity {np.nanmin(df.capacity_kg) if n_reach else float('nan'):.1f} kg -> {out}")


# --------------------------------------------------------------------------- voxels


def stage_voxels(shards: list[str], out_voxels: str, out_points: str, slice_json: str, log: str | None = None) -> None:
    sl = json.loads(slice_json)
    lg = Log(log, "voxels")
    pts = pd.concat([datasets.read(p) for p in shards], ignore_index=True).sort_values("point_id", ignore_index=True)
    xyz = pts[["x_m", "y_m", "z_m"]].to_numpy()
    grid = Grid.covering(xyz, sl["voxels"]["voxels"]["edge_m"])
    vm = voxelise(grid, xyz, pts.capacity_kg.to_numpy(), pts.reachable.to_numpy())
    idx = grid.all_indices()
    centres = grid.centres(idx)
    worst = vm.worst_point
    binding = np.where(worst >= 0, pts.binding.astype(str).to_numpy()[np.maximum(worst, 0)], "")
    vox = pd.DataFrame({"i": idx[:, 0], "j": idx[:, 1], "k": idx[:, 2],
                        "x_m": centres[:, 0], "y_m": centres[:, 1], "z_m": centres[:, 2],
                        "n_points": vm.n_points, "n_reachable": vm.n_reachable, "capacity_kg": vm.capacity_kg,
                        "binding": pd.Categorical(binding), "worst_point_id": np.where(worst >= 0, pts.point_id.to_numpy()[np.maximum(worst, 0)], -1)})
    pidx = grid.index(xyz)
    pts["i"], pts["j"], pts["k"] = pidx[:, 0], pidx[:, 1], pidx[:, 2]
    grid_meta = {"lower_m": grid.lower.tolist(), "shape": list(grid.shape), "edge_m": grid.edge_m}
    datasets.write(vox, out_voxels, datasets.provenance("voxels", sl, seed=sl["sample"]["sampling"]["seed"], grid=grid_meta))
    datasets.write(pts, out_points, datasets.provenance("voxels", sl, seed=sl["sample"]["sampling"]["seed"], grid=grid_meta))
    reach = vox.n_reachable > 0
    lg(f"grid {grid.shape} x {grid.edge_m} m: {int(reach.sum())} reachable voxels of {grid.n_voxels}; "
       f"{int((vox.n_points == 0).sum())} voxels without any sample; {len(pts)} points -> {out_voxels}")


# --------------------------------------------------------------------------- plan


def grid_of(vox: pd.DataFrame) -> Grid:
    """The voxel grid recorded in a voxels dataset's provenance."""
    g = vox.attrs["capmap"]["grid"]
    return Grid(lower=np.asarray(g["lower_m"], dtype=float), shape=tuple(g["shape"]), edge_m=float(g["edge_m"]))


WAYPOINT_COLUMNS = ["waypoint", "kind", "x_m", "y_m", "z_m", "i", "j", "k", "voxel_capacity_kg"]


def stage_plan(voxels: str, out: str, slice_json: str, log: str | None = None) -> None:
    """A* through the voxels that carry the task payload; a payload with no path is recorded
    (status ``no_path`` and the reason in the provenance, zero waypoints), not an error."""
    sl = json.loads(slice_json)
    task = sl["plan"]["task"]
    payload = float(task["payload_kg"])
    lg = Log(log, f"plan {payload:g} kg")
    vox = datasets.read(voxels)
    grid = grid_of(vox)
    cap = vox.capacity_kg.to_numpy()
    status, reason, cost, expanded = "ok", "", float("nan"), 0
    try:
        p = planning.plan(grid, cap, task["start_m"], task["goal_m"], payload)
        wv = p.waypoint_voxel
        df = pd.DataFrame({"waypoint": np.arange(len(p.waypoints)), "kind": p.waypoint_kind,
                           "x_m": p.waypoints[:, 0], "y_m": p.waypoints[:, 1], "z_m": p.waypoints[:, 2],
                           "i": wv[:, 0], "j": wv[:, 1], "k": wv[:, 2], "voxel_capacity_kg": cap[grid.flat(wv)]})
        cost, expanded = p.cost_m, p.expanded
        lg(f"{len(p.voxel_path)} voxels, {len(df)} waypoints, A* cost {cost:.3f} m, path {p.length_m:.3f} m, "
           f"{expanded} voxels expanded; weakest voxel on it {df.voxel_capacity_kg.min():.1f} kg")
    except planning.NoPath as exc:
        status, reason = "no_path", str(exc)
        df = pd.DataFrame({c: pd.Series(dtype=object if c == "kind" else float) for c in WAYPOINT_COLUMNS})
        lg(f"no path: {reason}")
    datasets.write(df, out, datasets.provenance("plan", sl, payload_kg=payload, status=status, reason=reason,
                                                 cost_m=cost, expanded=expanded))


# --------------------------------------------------------------------------- verify


def _deg(x):
    return np.rad2deg(x)


def _path_tables(name: str, res: verification.PathResult, arm: LockedArm, names: tuple[str, ...],
                 limit: np.ndarray, payload: float, planner: str) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """Time series, segment table and summary row of one verified path."""
    tl, tr, ld = res.timeline, res.tracking, res.loads
    y = ld.at(payload)
    ratio = np.abs(y) / limit  # (N, n_out), NaN where untracked
    bind_names = np.array(list(names) + ["untracked"])
    ts = pd.DataFrame({"path": name, "t_s": tl.t_s, "segment": tl.segment,
                       "phase": pd.Categorical.from_codes(tl.phase, list(trajectory.PHASES)),
                       "x_m": tl.p[:, 0], "y_m": tl.p[:, 1], "z_m": tl.p[:, 2],
                       "vx_mps": tl.v[:, 0], "vy_mps": tl.v[:, 1], "vz_mps": tl.v[:, 2],
                       "ax_mps2": tl.a[:, 0], "ay_mps2": tl.a[:, 1], "az_mps2": tl.a[:, 2]})
    for c, j in enumerate(arm.active_joint_numbers):
        ts[f"q_j{j}_deg"] = _deg(tr.q[:, c])
    for c, j in enumerate(arm.active_joint_numbers):
        ts[f"qd_j{j}_deg_s"] = _deg(ld.qd[:, c])
    for c, j in enumerate(arm.active_joint_numbers):
        ts[f"qdd_j{j}_deg_s2"] = _deg(ld.qdd[:, c])
    for c, col in enumerate(names):
        ts[col] = y[:, c]
    ts["state_capacity_kg"] = ld.capacity_kg
    ts["binding"] = bind_names[ld.binding]
    ts["tracked"] = ~np.isnan(tr.q).any(axis=1)
    ts["in_joint_range"] = tr.in_range.all(axis=1)

    seg_rows = []
    wp = np.concatenate([tl.p[[0]], [tl.p[tl.segment == k][-1] for k in range(len(tl.profiles))]])
    for k, prof in enumerate(tl.profiles):
        rows = tl.segment == k
        w = res.segment_worst[k]
        r = ratio[rows]
        peak = np.nanmax(r, axis=0) if np.isfinite(r).any() else np.full(len(names), np.nan)
        seg_rows.append({
            "path": name, "segment": k,
            "x0_m": wp[k, 0], "y0_m": wp[k, 1], "z0_m": wp[k, 2], "x1_m": wp[k + 1, 0], "y1_m": wp[k + 1, 1],
            "z1_m": wp[k + 1, 2], "length_m": prof.length_m, "duration_s": prof.duration_s, "v_peak_mps": prof.v_peak_mps,
            "capacity_kg": res.segment_capacity_kg[k],
            "binding": bind_names[ld.binding[w]] if w >= 0 else "",
            "t_worst_s": tl.t_s[w] if w >= 0 else np.nan,
            "margin_pct": 100 * (res.segment_capacity_kg[k] - payload) / payload if payload > 0 else np.nan,
            "peak_load_pct": 100 * np.nanmax(peak),
            "exceeded_at_payload": ",".join(n for n, v in zip(names, peak) if v > 1 + 1e-9),
            "tracked": bool(ts.tracked[rows].all()), "in_joint_range": bool(ts.in_joint_range[rows].all()),
        })
    seg = pd.DataFrame(seg_rows)

    peak_all = np.nanmax(ratio, axis=0) if np.isfinite(ratio).any() else np.full(len(names), np.nan)
    exceeded = [n for n, v in zip(names, peak_all) if v > 1 + 1e-9]
    worst_seg = int(np.argmin(res.segment_capacity_kg))
    excursions = verification.range_excursions(tr.in_range)
    notes = []
    for c, a, b in excursions:
        run = _deg(tr.q[a:b + 1, c])
        peak = run.max() if tr.q[a, c] > arm.q_upper[c] else run.min()  # the farthest beyond the stop
        notes.append(f"joint {arm.active_joint_numbers[c]} outside [{_deg(arm.q_lower[c]):g}, "
                     f"{_deg(arm.q_upper[c]):g}] deg for t = {tl.t_s[a]:.1f}..{tl.t_s[b]:.1f} s (peak {peak:.1f} deg)")
    range_note = "; ".join(notes)
    loads_ok = tr.ok and not exceeded
    mean_cap = float(np.mean(res.segment_capacity_kg))
    summary = {
        "path": name, "planner": planner, "segments": len(tl.profiles),
        "length_m": float(sum(p.length_m for p in tl.profiles)), "duration_s": float(tl.t_s[-1]),
        "tracking": "ok" if tr.ok else f"failed at t = {tl.t_s[tr.failed_at]:.1f} s: {tr.failure}",
        "start_branch_offset_deg": _deg(tr.start_offset_rad),
        "capacity_kg": float(res.segment_capacity_kg[worst_seg]),
        "binding": seg.binding[worst_seg], "weakest_segment": worst_seg,
        "mean_segment_capacity_kg": mean_cap,
        "margin_pct": 100 * (mean_cap - payload) / payload if payload > 0 else np.nan,
        "min_margin_pct": 100 * (res.segment_capacity_kg[worst_seg] - payload) / payload if payload > 0 else np.nan,
        "peak_load_pct": 100 * float(np.nanmax(peak_all)),
        "peak_load": names[int(np.nanargmax(peak_all))],
        "limits_exceeded_at_payload": ",".join(exceeded),
        "loads_ok": loads_ok, "joint_range": range_note or "ok",
        "feasible": loads_ok and not excursions,
    }
    return ts, seg, summary


def stage_verify(waypoints: str, out_timeseries: str, out_segments: str, out_csv: str, out_md: str, slice_json: str,
                 log: str | None = None) -> None:
    """Verify the direct line and the planned path (if any) carrying the task payload."""
    sl = json.loads(slice_json)
    robot, arm = _arm_from(sl)
    dyn = ArmDynamics(arm)
    cs, vt = sl["capacity"]["task"], sl["verify"]["task"]
    payload = float(vt["payload_kg"])
    lg = Log(log, f"verify {payload:g} kg")
    rotation = TaskConfig.rotation_from_rpy(cs["orientation_rpy_deg"])
    limit = LimitsConfig(**sl["capacity"]["limits"]).resolve(robot.n_joints).vector(arm)
    names = output_names(arm)
    q_ini = np.deg2rad(np.asarray(vt["q_ini_deg"], dtype=float))[arm.active]
    dt = float(sl["verify"]["verification"]["dt_s"])
    wp = datasets.read(waypoints)
    plan_meta = wp.attrs["capmap"]
    paths = {"direct": np.array([vt["start_m"], vt["goal_m"]], dtype=float)}
    if plan_meta["status"] == "ok":
        paths["planned"] = wp[["x_m", "y_m", "z_m"]].to_numpy()
    ts_parts, seg_parts, rows = [], [], []
    for name, pts in paths.items():
        res = verification.verify_path(dyn, pts, rotation, q_ini, cs["v_max_mps"], cs["a_max_mps2"], dt, limit)
        planner = "straight line" if name == "direct" else f"A*, {len(pts)} waypoints"
        ts, seg, row = _path_tables(name, res, arm, names, limit, payload, planner)
        ts_parts.append(ts)
        seg_parts.append(seg)
        rows.append(row)
        lg(f"{name}: {row['segments']} segments, {row['duration_s']:.1f} s, capacity {row['capacity_kg']:.1f} kg "
           f"({row['binding']}), mean segment capacity {row['mean_segment_capacity_kg']:.1f} kg = "
           f"{row['margin_pct']:+.1f}% vs {payload:g} kg; exceeded: {row['limits_exceeded_at_payload'] or 'none'}; "
           f"tracking {row['tracking']}; joint range {row['joint_range']}")
    if plan_meta["status"] != "ok":
        rows.append({"path": "planned", "planner": f"A*: {plan_meta['reason']}", "feasible": False})
        lg(f"planned: none ({plan_meta['reason']})")
    summary = pd.DataFrame(rows)
    summary.insert(0, "payload_kg", payload)
    ts = pd.concat(ts_parts, ignore_index=True)
    ts["path"] = ts.path.astype("category")
    ts["binding"] = ts.binding.astype("category")
    seg = pd.concat(seg_parts, ignore_index=True)
    prov = datasets.provenance("verify", sl, payload_kg=payload, limits=dict(zip(names, limit.tolist())),
                               plan_status=plan_meta["status"], plan_reason=plan_meta["reason"])
    datasets.write(ts, out_timeseries, prov)
    datasets.write(seg, out_segments, prov)
    write_table(summary, out_csv, out_md)


def write_table(df: pd.DataFrame, out_csv: str, out_md: str) -> None:
    """A summary table as CSV and as Markdown transposed: one column per row of ``df``, headed
    by its first two fields (e.g. payload and path)."""
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out_csv, index=False)

    def fmt(v):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (float, np.floating)):
            return "" if v is None else str(v)
        return "" if np.isnan(v) else f"{v:.1f}" if abs(v) >= 100 else f"{v:.4g}"

    md = df.iloc[:, 2:].map(fmt).T
    md.columns = [f"{a:g} kg, {b}" if df.columns[0] == "payload_kg" else f"{a} {b}"
                  for a, b in zip(df.iloc[:, 0], df.iloc[:, 1])]
    Path(out_md).write_text(md.to_markdown() + "\n")


def stage_verify_plots(voxels: str, timeseries: str, out_workspace: str, out_torques: str, out_force: str,
                       out_moment: str, slice_json: str, log: str | None = None) -> None:
    """Capacity workspace with both paths; torques, base force and base moment against their limits."""
    from capmap import plots

    vox, ts = datasets.read(voxels), datasets.read(timeseries)
    meta = ts.attrs["capmap"]
    payload, limits = meta["payload_kg"], meta["limits"]
    plots.workspace_paths(vox, ts, payload, out_workspace)
    tau = [c for c in limits if c.startswith("tau_")]
    plots.load_series(ts, tau, limits, f"Joint torques carrying {payload:g} kg", out_torques)
    plots.load_series(ts, [c for c in limits if c.startswith("base_f")], limits,
                      f"Base disturbance force carrying {payload:g} kg", out_force)
    plots.load_series(ts, [c for c in limits if c.startswith("base_m")], limits,
                      f"Base disturbance moment carrying {payload:g} kg", out_moment)
    Log(log, f"verify plots {payload:g} kg")(f"-> {out_workspace}, {out_torques}, {out_force}, {out_moment}")


def stage_concat_summary(tables: list[str], out_csv: str, out_md: str, what: str, log: str | None = None) -> None:
    """Several summary CSVs (every payload's verification, every follow case) in one table."""
    df = pd.concat([pd.read_csv(t) for t in tables], ignore_index=True)
    write_table(df, out_csv, out_md)
    Log(log, f"{what} summary")(f"{len(df)} rows -> {out_csv}")


# --------------------------------------------------------------------------- follow


def _follow_setup(case: str, sl: dict, waypoints: str | None):
    """(arm, waypoints (W, 3), rotation, q_start, payload, tau_max, v, a, j, period, catch_up, label) of a case."""
    from capmap.locking import free

    fol = sl["follow"]
    if case == "space":
        sp = fol["space"]
        robot, arm = _arm_from(sl)
        task, vt = sl["capacity"]["task"], sl["verify"]["task"]
        rotation = TaskConfig.rotation_from_rpy(task["orientation_rpy_deg"])
        wp = datasets.read(waypoints)
        if wp.attrs["capmap"]["status"] == "ok":
            pts, label = wp[["x_m", "y_m", "z_m"]].to_numpy(), "planned path"
        else:
            pts, label = np.array([vt["start_m"], vt["goal_m"]], dtype=float), "direct line (no planned path)"
        q0 = np.deg2rad(np.asarray(vt["q_ini_deg"], dtype=float))[arm.active]
        tau = per_item(sp["joint_torque_nm"], robot.n_joints, "follow.space.joint_torque_nm")[arm.active]
        return (arm, pts, rotation, q0, float(sp["payload_kg"]), tau, task["v_max_mps"], task["a_max_mps2"],
                sp["j_max_mps3"], fol["period_s"], sp["catch_up_hz"], label)
    g = fol["ground"]
    robot = load(g["robot"])
    arm = free(robot)
    q0 = np.deg2rad(np.asarray(g["q_start_deg"], dtype=float))
    T0 = arm.fk(q0[None])[0]
    pts = np.array([T0[:3, 3], T0[:3, 3] + np.asarray(g["line_m"], dtype=float)])
    tau = per_item(g["joint_torque_nm"], robot.n_joints, "follow.ground.joint_torque_nm")
    return (arm, pts, T0[:3, :3], q0, float(g["payload_kg"]), tau, g["v_max_mps"], g["a_max_mps2"], g["j_max_mps3"],
            fol["period_s"], g["catch_up_hz"], "straight line")


def stage_follow(case: str, out_timeseries: str, out_toppra: str, out_csv: str, out_md: str, slice_json: str,
                 waypoints: str | None = None, log: str | None = None) -> None:
    """Torque-limited following of a case's path, segment by segment, and TOPP-RA on the same."""
    from capmap import following
    from capmap.toppra_reference import time_optimal

    sl = json.loads(slice_json)
    lg = Log(log, f"follow {case}")
    arm, pts, rotation, q, payload, tau_max, v, a, j, period, catch_up, label = _follow_setup(case, sl, waypoints)
    joints = arm.active_joint_numbers
    parts, tparts, seg_rows = [], [], []
    t_off = t_off_topp = s_off = 0.0
    for k in range(len(pts) - 1):
        t0 = time.perf_counter()
        seg = following.follow_segment(arm, pts[k], pts[k + 1], rotation, q, payload, tau_max, v, a, j, period,
                                       catch_up)
        el = time.perf_counter() - t0
        top = time_optimal(arm, seg.table, payload, tau_max, v, a, sample_dt_s=period)
        r = seg.result
        df = pd.DataFrame({"case": case, "segment": k, "t_s": t_off + r.t_s, "s_cmd_m": s_off + r.s_cmd,
                           "sd_cmd_mps": r.sd_cmd, "sdd_cmd_mps2": r.sdd_cmd, "s_m": s_off + r.s, "sd_mps": r.sd,
                           "sdd_mps2": r.sdd, "lag_m": r.s_cmd - r.s, "limited": r.limited,
                           "infeasible": r.infeasible})
        for c, jn in enumerate(joints):
            df[f"tau_cmd_j{jn}_nm"] = seg.tau_cmd[:, c]
        for c, jn in enumerate(joints):
            df[f"tau_j{jn}_nm"] = seg.tau[:, c]
        for c, jn in enumerate(joints):
            df[f"q_j{jn}_deg"] = np.rad2deg(seg.q[:, c])
        df["deviation_m"] = seg.deviation_m
        df["deviation_rad"] = seg.deviation_rad
        parts.append(df)
        tdf = pd.DataFrame({"case": case, "segment": k, "t_s": t_off_topp + top.t_s, "s_m": s_off + top.s,
                            "sd_mps": top.sd})
        for c, jn in enumerate(joints):
            tdf[f"tau_j{jn}_nm"] = top.tau[:, c]
        tparts.append(tdf)
        seg_rows.append({"segment": k, "length_m": seg.table.length_m, "command_s": seg.command.duration_s,
                         "follower_s": r.duration_s, "toppra_s": top.duration_s,
                         "follower_peak": float((np.abs(seg.tau) / tau_max).max()),
                         "toppra_peak": float((np.abs(top.tau) / tau_max).max())})
        lg(f"segment {k + 1}/{len(pts) - 1}: {seg.table.length_m:.3f} m, command {seg.command.duration_s:.3f} s, "
           f"follower {r.duration_s:.3f} s ({int(r.limited.sum())} of {len(r.t_s)} periods limited), "
           f"TOPP-RA {top.duration_s:.3f} s; {el:.2f} s wall incl. path preparation and exact evaluation")
        t_off += r.duration_s
        t_off_topp += top.duration_s
        s_off += seg.table.length_m
        q = seg.q[-1]
    ts = pd.concat(parts, ignore_index=True)
    tp = pd.concat(tparts, ignore_index=True)
    segs = pd.DataFrame(seg_rows)
    tau_cols = [f"tau_j{jn}_nm" for jn in joints]
    ratio_f = np.abs(ts[tau_cols].to_numpy()) / tau_max
    ratio_c = np.abs(ts[[f"tau_cmd_j{jn}_nm" for jn in joints]].to_numpy()) / tau_max
    ratio_t = np.abs(tp[tau_cols].to_numpy()) / tau_max
    summary = pd.DataFrame([{
        "case": case, "robot": arm.robot.name, "path": label, "payload_kg": payload, "segments": len(segs),
        "length_m": float(segs.length_m.sum()), "torque_limits_nm": " ".join(f"{t:g}" for t in tau_max),
        "command_duration_s": float(segs.command_s.sum()), "follower_duration_s": float(segs.follower_s.sum()),
        "toppra_duration_s": float(segs.toppra_s.sum()),
        "duration_ratio": float(segs.follower_s.sum() / segs.toppra_s.sum()),
        "command_vs_toppra_ratio": float(segs.command_s.sum() / segs.toppra_s.sum()),
        "command_peak_torque_pct": 100 * float(ratio_c.max()),
        "follower_peak_torque_pct": 100 * float(ratio_f.max()),
        "follower_max_violation_pct": 100 * max(0.0, float(ratio_f.max()) - 1),
        "toppra_peak_torque_pct": 100 * float(ratio_t.max()),
        "toppra_max_violation_pct": 100 * max(0.0, float(ratio_t.max()) - 1),
        "saturated_joints": " ".join(f"j{jn}" for c, jn in enumerate(joints) if ratio_f[:, c].max() > 0.999),
        "limited_periods_pct": 100 * float(ts.limited.mean()),
        "infeasible_periods": int(ts.infeasible.sum()),
        "max_lag_m": float(ts.lag_m.max()),
        "max_deviation_m": float(ts.deviation_m.max()), "max_deviation_rad": float(ts.deviation_rad.max()),
        "period_s": period,
    }])
    prov = datasets.provenance("follow", sl, case=case, torque_limits_nm=dict(zip(tau_cols, tau_max.tolist())),
                               payload_kg=payload)
    datasets.write(ts, out_timeseries, prov)
    datasets.write(tp, out_toppra, prov)
    write_table(summary, out_csv, out_md)
    row = summary.iloc[0]
    lg(f"{row.length_m:.3f} m in {row.follower_duration_s:.3f} s vs TOPP-RA {row.toppra_duration_s:.3f} s "
       f"(ratio {row.duration_ratio:.3f}); peak torque {row.follower_peak_torque_pct:.3f}% of limit "
       f"(TOPP-RA {row.toppra_peak_torque_pct:.3f}%); command would need {row.command_peak_torque_pct:.1f}%; "
       f"max path deviation {row.max_deviation_m:.2e} m")


def stage_follow_plots(timeseries: str, toppra: str, out_s: str, out_torques: str, slice_json: str,
                       log: str | None = None) -> None:
    from capmap import plots

    ts, tp = datasets.read(timeseries), datasets.read(toppra)
    meta = ts.attrs["capmap"]
    plots.follow_progress(ts, tp, meta["case"], out_s)
    plots.follow_torques(ts, meta["torque_limits_nm"], meta["case"], out_torques)
    Log(log, f"follow plots {meta['case']}")(f"-> {out_s}, {out_torques}")


# --------------------------------------------------------------------------- summary and catalogue


def stage_summary(voxels: str, points: str, out_csv: str, out_md: str, out_png: str, slice_json: str,
                  log: str | None = None) -> None:
    """Capacity summary table (CSV + Markdown) and a capacity-coloured workspace figure."""
    from capmap import plots

    vox, pts = datasets.read(voxels), datasets.read(points)
    reach_v = vox[vox.n_reachable > 0]
    reach_p = pts[pts.reachable]
    q = reach_v.capacity_kg.quantile([0.0, 0.05, 0.5, 0.95, 1.0]) if len(reach_v) else pd.Series(np.nan, [0, .05, .5, .95, 1])
    rows = [
        ("points evaluated", len(pts)), ("points reachable at task orientation", len(reach_p)),
        ("motion states evaluated", int(pts.n_states.sum())),
        ("voxels in grid", len(vox)), ("voxels without samples", int((vox.n_points == 0).sum())),
        ("reachable voxels", len(reach_v)),
        ("voxel capacity min [kg]", round(q.iloc[0], 1)), ("voxel capacity p5 [kg]", round(q.iloc[1], 1)),
        ("voxel capacity median [kg]", round(q.iloc[2], 1)), ("voxel capacity p95 [kg]", round(q.iloc[3], 1)),
        ("voxel capacity max [kg]", round(q.iloc[4], 1)),
    ]
    for name, count in reach_p.binding.astype(str).value_counts().items():
        rows.append((f"points bound by {name}", int(count)))
    table = pd.DataFrame(rows, columns=["quantity", "value"])
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(out_csv, index=False)
    Path(out_md).write_text(table.to_markdown(index=False) + "\n")
    plots.capacity_map(vox, out_png)
    Log(log, "summary")(f"{len(reach_v)} reachable voxels, median capacity {q.iloc[2]:.1f} kg -> {out_csv}, {out_png}")


def stage_catalogue(paths: list[str], out: str, log: str | None = None) -> None:
    cat = datasets.catalogue(paths)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    cat.to_parquet(out, index=False)
    Log(log, "catalogue")(f"{len(cat)} datasets -> {out}")


def run(fn, log: str | None = None, **kwargs) -> None:
    """Entry for the thin Snakemake scripts: call ``fn`` with one-line errors."""
    with one_line_errors(log):
        fn(log=log, **kwargs)
