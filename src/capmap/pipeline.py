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
from capmap import datasets, ik, sampling
from capmap.config import DirectionsConfig, LimitsConfig, LockConfig, SamplingConfig, TaskConfig
from capmap.dynamics import ArmDynamics
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
