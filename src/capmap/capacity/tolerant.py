"""The failure-tolerant map: per voxel, the capacity left whichever single joint fails at whichever angle.

Given every joint's lock sweep on one grid (:mod:`capmap.capacity.lock_sweep`), a voxel's
failure-tolerant capacity is the minimum over the joints and their swept lock angles of the locked
maps' values there, with the (joint, angle) that binds. A voxel that some lock leaves unreachable has
none (NaN, ``reachable_every_failure`` False; the binding lock is one that leaves it). The same minimum
joint by joint (``tolerant_j{j}_capacity_kg``: whatever angle joint j fails at) says which failures
decide. Beside them, the best over the same locks: every lock is a posture the healthy arm can take, so
this is a lower bound of the healthy arm's capacity there (each voxel at its best swept lock), on the
same grid and directions.

The minimum is taken over the swept angles, so between two of them the true minimum can be lower: the
table also holds the minimum over every other swept angle (the sweep at twice the step), and the
change from it is the convergence the summary states. No file I/O."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.errors import CapmapError

__all__ = ["TOLERANT_COLUMNS", "SUMMARY_COLUMNS", "failure_tolerant", "tolerance_summary", "lock_reach"]

TOLERANT_COLUMNS = ["i", "j", "k", "x_m", "y_m", "z_m", "tolerant_capacity_kg", "reachable_every_failure",
                    "binding_joint", "binding_angle_deg", "tolerant_capacity_double_step_kg", "healthy_capacity_kg",
                    "healthy_joint", "healthy_angle_deg", "n_locks", "n_locks_reaching"]
"""advice/tolerant.parquet: one row per voxel of the sweeps' grid, then ``tolerant_j{j}_capacity_kg`` per joint."""

SUMMARY_COLUMNS = ["scope", "payload_kg", "volume_m3", "reachable_m3", "double_step_drop_max_rel"]
"""advice/tolerant_summary.parquet: per scope (``healthy``, ``joint {j}``, ``any joint``) and task payload, the
volume carrying the payload and the volume reached."""

_VOXEL = ["i", "j", "k"]


def _every_other(sweeps: pd.DataFrame) -> pd.DataFrame:
    """The rows of every other swept angle of each joint (its sweep at twice the step)."""
    rank = sweeps.groupby("joint").angle_deg.rank(method="dense").astype(int) - 1
    return sweeps[rank % 2 == 0]


def _least(sweeps: pd.DataFrame) -> pd.DataFrame:
    """Per voxel (i, j, k), sorted: the least value over the locks (an unreachable lock below every value:
    -1) and its lock."""
    v = sweeps.capacity_kg.fillna(-1.0)  # capacities are >= 0: an unreachable lock binds first
    rows = v.groupby([sweeps[c] for c in _VOXEL], sort=True).idxmin().to_numpy()
    out = sweeps.loc[rows, [*_VOXEL, "x_m", "y_m", "z_m", "joint", "angle_deg"]].reset_index(drop=True)
    out["least_kg"] = v.loc[rows].to_numpy()
    return out


def _value(least_kg: np.ndarray) -> np.ndarray:
    return np.where(least_kg >= 0, least_kg, np.nan)


def failure_tolerant(sweeps: pd.DataFrame) -> pd.DataFrame:
    """The failure-tolerant map of ``sweeps`` (every joint's lock sweep,
    :data:`capmap.capacity.lock_sweep.SWEEP_COLUMNS`, concatenated; each voxel must appear once per (joint,
    angle), as sweeps on the same points do): :data:`TOLERANT_COLUMNS` and one ``tolerant_j{j}_capacity_kg``
    per joint, one row per voxel, sorted by (i, j, k)."""
    locks = sweeps[["joint", "angle_deg"]].drop_duplicates()
    per_voxel = sweeps.groupby(_VOXEL).size()
    if not len(sweeps) or (per_voxel != len(locks)).any():
        raise CapmapError(f"the lock sweeps are not on one set of voxels ({len(locks)} locks, voxels holding "
                          f"{per_voxel.min() if len(per_voxel) else 0}..{per_voxel.max() if len(per_voxel) else 0} "
                          "of them)")
    least = _least(sweeps)
    by_voxel = [sweeps[c] for c in _VOXEL]
    best = sweeps.capacity_kg.fillna(-1.0).groupby(by_voxel, sort=True).idxmax().to_numpy()
    best_kg = sweeps.capacity_kg.to_numpy()[best]
    reached = np.isfinite(best_kg)
    out = pd.DataFrame({
        "i": least.i, "j": least.j, "k": least.k, "x_m": least.x_m, "y_m": least.y_m, "z_m": least.z_m,
        "tolerant_capacity_kg": _value(least.least_kg.to_numpy()),
        "reachable_every_failure": least.least_kg.to_numpy() >= 0,
        "binding_joint": least.joint.astype(int), "binding_angle_deg": least.angle_deg,
        "tolerant_capacity_double_step_kg": _value(_least(_every_other(sweeps)).least_kg.to_numpy()),
        "healthy_capacity_kg": best_kg,
        "healthy_joint": np.where(reached, sweeps.joint.to_numpy()[best], -1),
        "healthy_angle_deg": np.where(reached, sweeps.angle_deg.to_numpy()[best], np.nan),
        "n_locks": len(locks),
        "n_locks_reaching": sweeps.capacity_kg.notna().groupby(by_voxel, sort=True).sum().to_numpy().astype(int)})
    for j, part in sweeps.groupby("joint", sort=True):
        out[f"tolerant_j{int(j)}_capacity_kg"] = _value(_least(part).least_kg.to_numpy())
    return out


def lock_reach(sweeps: pd.DataFrame) -> pd.DataFrame:
    """Per lock (joint, angle_deg): the voxels it reaches (``n_reached``), fewest first."""
    g = sweeps.capacity_kg.notna().groupby([sweeps.joint, sweeps.angle_deg]).sum()
    return g.rename("n_reached").reset_index().sort_values(["n_reached", "joint", "angle_deg"], ignore_index=True)


def tolerance_summary(tol: pd.DataFrame, edge_m: float, payloads_kg) -> pd.DataFrame:
    """:data:`SUMMARY_COLUMNS`: per scope (the healthy arm, each joint failing at any angle, any joint) and
    payload, the volume [m^3] carrying it and the volume reached; and for any joint the convergence of the
    minimum over angles (the largest drop, relative, from the sweep at twice the step to the sweep, over
    the failure-tolerant voxels; NaN elsewhere)."""
    v = edge_m**3
    tol_kg = tol.tolerant_capacity_kg.to_numpy()
    coarse = tol.tolerant_capacity_double_step_kg.to_numpy()
    ok = np.isfinite(tol_kg) & np.isfinite(coarse) & (coarse > 0)
    drop = float(np.max((coarse[ok] - tol_kg[ok]) / coarse[ok], initial=0.0))
    scopes = [("healthy", "healthy_capacity_kg")]
    scopes += [(f"joint {c[len('tolerant_j'):-len('_capacity_kg')]}", c) for c in tol.columns
               if c.startswith("tolerant_j")]
    scopes += [("any joint", "tolerant_capacity_kg")]
    rows = []
    for scope, col in scopes:
        c = tol[col].to_numpy()
        for m in payloads_kg:
            rows.append({"scope": scope, "payload_kg": float(m), "volume_m3": float(np.sum(np.nan_to_num(c, nan=-1) >= m) * v),
                         "reachable_m3": float(np.isfinite(c).sum() * v),
                         "double_step_drop_max_rel": drop if scope == "any joint" else np.nan})
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
