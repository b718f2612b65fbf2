"""The capacity family's tables and their column schemas (units in the names): the robot model's
joints, the sampled points, the per-point capacities (every IK branch x every direction), the voxel
map; and the grid a voxel table records in its provenance. Built from numerics results, no file I/O."""

from __future__ import annotations

import time

import numpy as np
import pandas as pd
import pinocchio as pin

from capmap.capacity import sampling
from capmap.capacity.directions import AXIS_LABELS, angles_deg
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.voxels import Grid, voxelise
from capmap.core.reduction import LockedArm
from capmap.core.robot import Robot

__all__ = ["AXIS_COLUMNS", "model_table", "sample_table", "capacity_table", "voxel_table", "axes_stored", "grid_meta", "grid_of",
           "configuration_voxels"]

AXIS_COLUMNS = [f"capacity_along_{label.replace('+', '_plus_').replace('-', '_minus_')}_kg" for label in AXIS_LABELS]
"""Capacity for moves along the 13 grid axes, named as Python identifiers: 'capacity_along_x_kg', ...,
'capacity_along_x_plus_y_kg', 'capacity_along_x_minus_y_minus_z_kg' (axis label 'x-y-z')."""


def model_table(robot: Robot) -> pd.DataFrame:
    """Joint/link table of a built robot (angles in deg), with each joint's drive: reflected rotor inertia
    armature_kgm2 and friction coulomb_nm, viscous_nms."""
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
            "effort_nm": np.nan if robot.effort_limit_nm is None else robot.effort_limit_nm[j - 1],  # the URDF's
            "placement_x_m": M.translation[0], "placement_y_m": M.translation[1], "placement_z_m": M.translation[2],
            "placement_roll_deg": rpy[0], "placement_pitch_deg": rpy[1], "placement_yaw_deg": rpy[2],
            "mass_kg": inertia.mass, "com_x_m": inertia.lever[0], "com_y_m": inertia.lever[1], "com_z_m": inertia.lever[2],
            "ixx_kgm2": I[0, 0], "iyy_kgm2": I[1, 1], "izz_kgm2": I[2, 2], "ixy_kgm2": I[0, 1], "ixz_kgm2": I[0, 2],
            "iyz_kgm2": I[1, 2], "armature_kgm2": m.armature[j - 1], "coulomb_nm": m.friction[j - 1],
            "viscous_nms": m.damping[j - 1],
        })
    return pd.DataFrame(rows)


def sample_table(arm: LockedArm, sc, edge_m: float | None, log=None) -> pd.DataFrame:
    """The sampled points of the locked arm: joint-space Monte Carlo (seeded), plus for
    ``voxel_fill`` every voxel (of edge_m) of their bounding box. ``sc``: the sampling settings
    (mode, n_points, seed, jitter_per_voxel: a :class:`capmap.config.capacity.SamplingConfig`)."""
    rng = np.random.default_rng(sc.seed)
    _, pos = sampling.joint_samples(arm, sc.n_points, rng)
    source = np.zeros(len(pos), dtype=int)
    if sc.mode == "voxel_fill":
        grid = Grid.covering(pos, edge_m)
        fill, kind = sampling.voxel_fill(grid, sc.jitter_per_voxel, rng)
        pos = np.concatenate([pos, fill])
        source = np.concatenate([source, kind + 1])
        if log:
            log.info(f"voxel_fill: grid {grid.shape} of {grid.edge_m} m = {grid.n_voxels} voxels, "
                     f"+{len(fill)} points (centre + {sc.jitter_per_voxel} jittered each)")
    return pd.DataFrame({"point_id": np.arange(len(pos)), "x_m": pos[:, 0], "y_m": pos[:, 1], "z_m": pos[:, 2],
                         "source": pd.Categorical.from_codes(source, ["joint_sample", "voxel_centre", "voxel_jitter"])})


def capacity_table(problem: CapacityProblem, ids: np.ndarray, pos: np.ndarray, log=None, chunk: int = 500) -> pd.DataFrame:
    """Per-point capacity table of ``problem`` for points ``pos`` (N, 3) m with ids (N,) (all IK
    branches x all directions, per-axis minima along the problem's axes); progress to ``log`` (a
    logger) every chunk."""
    arm, dirs = problem.arm, problem.directions
    parts = []
    t0, states = time.perf_counter(), 0
    for start in range(0, len(pos), chunk):
        rows = slice(start, start + chunk)
        sol, pc = problem.solve(pos[rows], chunk)
        states += int(pc.n_states.sum())
        reach = sol.n_solutions > 0
        alpha, beta = angles_deg(pc.worst_u)  # off the set (exact): from the direction itself
        on = pc.direction >= 0
        d = np.where(on, pc.direction, 0)
        br = np.where(pc.branch >= 0, pc.branch, 0)
        q_worst = np.where(reach[:, None], sol.q[np.arange(len(br)), br], np.nan)
        part = pd.DataFrame({
            "point_id": ids[rows], "x_m": pos[rows, 0], "y_m": pos[rows, 1], "z_m": pos[rows, 2],
            "reachable": reach, "n_branches": sol.n_solutions, "capacity_kg": pc.capacity_kg,
            "binding": np.where(reach, np.array(pc.names + ("",))[pc.binding], ""),
            "worst_branch": pc.branch,
            "worst_alpha_deg": np.where(on, dirs.alpha_deg[d], alpha),
            "worst_beta_deg": np.where(on, dirs.beta_deg[d], beta),
            "worst_ux": pc.worst_u[:, 0], "worst_uy": pc.worst_u[:, 1], "worst_uz": pc.worst_u[:, 2],
            "n_states": pc.n_states,
        })
        for c, j in enumerate(arm.active_joint_numbers):
            part[f"worst_q_j{j}_deg"] = np.rad2deg(q_worst[:, c])
        for c, col in enumerate(AXIS_COLUMNS):
            part[col] = pc.axis_capacity_kg[:, c]
        parts.append(part)
        if log:
            done = min(start + chunk, len(pos))
            el = time.perf_counter() - t0
            log.info(f"{done}/{len(pos)} points ({done / len(pos):.0%}), {states / el:,.0f} states/s, "
                     f"eta {el / done * (len(pos) - done):.0f} s")
    df = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()
    if len(df):
        df["binding"] = df["binding"].astype("category")
    return df


def voxel_table(pts: pd.DataFrame, edge_m: float) -> tuple[pd.DataFrame, Grid]:
    """Voxels of edge_m covering the capacity points (each voxel: the minimum over its points);
    adds the voxel indices i, j, k to ``pts``."""
    xyz = pts[["x_m", "y_m", "z_m"]].to_numpy()
    grid = Grid.covering(xyz, edge_m)
    vm = voxelise(grid, xyz, pts.capacity_kg.to_numpy(), pts.reachable.to_numpy())
    idx = grid.all_indices()
    centres = grid.centres(idx)
    worst = vm.worst_point
    binding = np.where(worst >= 0, pts.binding.astype(str).to_numpy()[np.maximum(worst, 0)], "")
    pidx = grid.index(xyz)
    axis = np.full((grid.n_voxels, len(AXIS_COLUMNS)), np.nan)
    if AXIS_COLUMNS[0] in pts:
        r = pts.reachable.to_numpy() & (pidx[:, 0] >= 0)
        axis[:] = np.inf
        np.fmin.at(axis, grid.flat(pidx[r]), pts.loc[r, AXIS_COLUMNS].to_numpy())
        axis[vm.n_reachable == 0] = np.nan
    wxyz = np.where(worst[:, None] >= 0, xyz[np.maximum(worst, 0)], np.nan)
    vox = pd.DataFrame({"i": idx[:, 0], "j": idx[:, 1], "k": idx[:, 2],
                        "x_m": centres[:, 0], "y_m": centres[:, 1], "z_m": centres[:, 2],
                        "n_points": vm.n_points, "n_reachable": vm.n_reachable, "reachable": vm.n_reachable > 0,
                        "capacity_kg": vm.capacity_kg,
                        "binding": pd.Categorical(binding),
                        "worst_point_id": np.where(worst >= 0, pts.point_id.to_numpy()[np.maximum(worst, 0)], -1),
                        "worst_x_m": wxyz[:, 0], "worst_y_m": wxyz[:, 1], "worst_z_m": wxyz[:, 2]})
    for c, col in enumerate(AXIS_COLUMNS):
        vox[col] = axis[:, c]
    pts["i"], pts["j"], pts["k"] = pidx[:, 0], pidx[:, 1], pidx[:, 2]
    return vox, grid


def axes_stored(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` with its capacities along the grid axes (:data:`AXIS_COLUMNS`) as float32 rounded toward
    zero capacity: at most 1.2e-7 relative below the computed value, never above it (a stored capacity
    must not overstate); half their size in the per-point and per-configuration tables."""
    out = df.copy()
    for col in AXIS_COLUMNS:
        if col in out:
            x = out[col].to_numpy(dtype=float)
            y = x.astype(np.float32)
            with np.errstate(invalid="ignore"):
                up = y.astype(float) > x
            y[up] = np.nextafter(y[up], np.float32(-np.inf))
            out[col] = y
    return out


def grid_meta(grid: Grid) -> dict:
    """The grid as recorded in a voxels dataset's provenance (read back by :func:`grid_of`)."""
    return {"lower_m": grid.lower.tolist(), "shape": list(grid.shape), "edge_m": grid.edge_m}


def grid_of(vox: pd.DataFrame) -> Grid:
    """The voxel grid recorded in a voxels dataset's provenance."""
    g = vox.attrs["capmap"]["grid"]
    return Grid(lower=np.asarray(g["lower_m"], dtype=float), shape=tuple(g["shape"]), edge_m=float(g["edge_m"]))


def configuration_voxels(vox: pd.DataFrame, conf: pd.DataFrame, name: str) -> pd.DataFrame | None:
    """The voxel map of one configuration ``name``, in the voxel map's layout: ``vox`` (the all-branch
    map, every voxel of the grid) with capacity_kg, binding, the worst point, the per-axis values and
    n_reachable (the evaluated points holding the configuration) of that configuration from ``conf``
    (voxels/configurations.parquet); a voxel it does not reach: NaN, n_reachable 0. ``bound_kg``: the
    all-branch value. None when ``conf`` has no rows (no refinement: no configuration maps)."""
    if not len(conf):
        return None
    mine = conf[conf.configuration.astype(str) == name]
    out = vox.copy()
    out["bound_kg"] = vox.capacity_kg.where(vox.n_reachable > 0)
    grid = grid_of(vox)
    rows = grid.flat(mine[["i", "j", "k"]].to_numpy())
    for col in ("capacity_kg", "worst_x_m", "worst_y_m", "worst_z_m", *AXIS_COLUMNS):
        values = np.full(len(out), np.nan)
        values[rows] = mine[col].to_numpy()
        out[col] = values
    n = np.zeros(len(out), dtype=int)
    n[rows] = mine.n_points.to_numpy()
    out["n_reachable"] = n
    binding = np.full(len(out), "", dtype=object)
    binding[rows] = mine.binding.astype(str).to_numpy()
    out["binding"] = pd.Categorical(binding)
    out.attrs = {**vox.attrs}
    return out
