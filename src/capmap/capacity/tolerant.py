"""The failure-tolerant map: per voxel, the capacity left whichever single joint fails at whichever angle.

Given every joint's lock sweep on one grid (:mod:`capmap.capacity.lock_sweep`), a voxel's
failure-tolerant capacity is the minimum over the joints and their swept lock angles of the locked
maps' values there, with the (joint, angle) that binds. A lock counts as reaching a voxel only if it
reaches every sampled point in it; a voxel that some lock leaves (wholly or in part) has no guarantee
(NaN, ``reachable_every_failure`` False; the binding lock is, of those leaving it, the one that reaches
the fewest voxels; none where no lock reaches it). The same minimum joint by joint
(``tolerant_j{j}_capacity_kg``: whatever angle joint j fails at) says which failures decide. Beside them,
the best over the same locks: every lock is a posture the healthy arm can take, so this is a lower bound of
the healthy arm's capacity there (each voxel at its best swept lock), on the same grid and directions.

The minimum is taken over the swept angles: between two of them the true minimum can be lower, so every
value is an upper bound of the guarantee, not the guarantee. The table also holds each minimum over every
other swept angle (the sweep at twice the step, ``*_double_step_kg``); how much halving the step lowered
them is the convergence the summary states per scope. No file I/O."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.errors import CapmapError

__all__ = ["TOLERANT_COLUMNS", "SUMMARY_COLUMNS", "failure_tolerant", "tolerance_summary", "lock_reach", "scopes"]

TOLERANT_COLUMNS = ["i", "j", "k", "x_m", "y_m", "z_m", "tolerant_capacity_kg", "reachable_every_failure",
                    "binding_joint", "binding_angle_deg", "tolerant_capacity_double_step_kg", "healthy_capacity_kg",
                    "healthy_joint", "healthy_angle_deg", "n_locks", "n_locks_reaching"]
"""advice/tolerant.parquet: one row per voxel of the sweeps' grid, then per joint j ``tolerant_j{j}_capacity_kg``
and ``tolerant_j{j}_capacity_double_step_kg``."""

SUMMARY_COLUMNS = ["scope", "payload_kg", "volume_m3", "volume_double_step_m3", "reachable_m3", "double_step_drop_max_rel"]
"""advice/tolerant_summary.parquet: per scope (``healthy``, ``joint {j}``, ``any joint``) and task payload, the
volume carrying the payload (on the sweep, and on the sweep at twice the step), the volume reached, and the
largest relative drop of a voxel's value from twice the step to the step (NaN: no voxel to compare)."""

_VOXEL = ["i", "j", "k"]


def _every_other(sweeps: pd.DataFrame) -> pd.DataFrame:
    """The rows of every other swept angle of each joint (its sweep at twice the step)."""
    rank = sweeps.groupby("joint").angle_deg.rank(method="dense").astype(int) - 1
    return sweeps[rank % 2 == 0]


def _value(sweeps: pd.DataFrame) -> pd.Series:
    """Each row's value for a guarantee: its capacity where the lock reaches every point of the voxel, else -1
    (below every capacity: a lock leaving the voxel binds first)."""
    whole = (sweeps.n_reachable == sweeps.n_points) & sweeps.capacity_kg.notna()
    return sweeps.capacity_kg.where(whole, -1.0)


def _least(sweeps: pd.DataFrame) -> pd.DataFrame:
    """Per voxel (i, j, k), sorted: the least value over the locks and its lock (``sweeps`` in the order ties
    go by: the first row of a voxel's least wins)."""
    v = _value(sweeps)
    rows = v.groupby([sweeps[c] for c in _VOXEL], sort=True).idxmin().to_numpy()
    out = sweeps.loc[rows, [*_VOXEL, "x_m", "y_m", "z_m", "joint", "angle_deg"]].reset_index(drop=True)
    out["least_kg"] = v.loc[rows].to_numpy()
    return out


def _guarantee(least_kg: np.ndarray) -> np.ndarray:
    return np.where(least_kg >= 0, least_kg, np.nan)


def lock_reach(sweeps: pd.DataFrame) -> pd.DataFrame:
    """Per lock (joint, angle_deg): the voxels it reaches wholly (``n_reached``), fewest first."""
    g = (_value(sweeps) >= 0).groupby([sweeps.joint, sweeps.angle_deg]).sum()
    return g.rename("n_reached").reset_index().sort_values(["n_reached", "joint", "angle_deg"], ignore_index=True)


def failure_tolerant(sweeps: pd.DataFrame) -> pd.DataFrame:
    """The failure-tolerant map of ``sweeps`` (every joint's lock sweep,
    :data:`capmap.capacity.lock_sweep.SWEEP_COLUMNS`, concatenated; each voxel must appear once per (joint,
    angle), as sweeps on the same points do): :data:`TOLERANT_COLUMNS` and the per-joint columns, one row per
    voxel, sorted by (i, j, k)."""
    locks = sweeps[["joint", "angle_deg"]].drop_duplicates()
    per_voxel = sweeps.groupby(_VOXEL).size()
    if not len(sweeps) or (per_voxel != len(locks)).any():
        raise CapmapError(f"the lock sweeps are not on one set of voxels ({len(locks)} locks, voxels holding "
                          f"{per_voxel.min() if len(per_voxel) else 0}..{per_voxel.max() if len(per_voxel) else 0} "
                          "of them)")
    rank = lock_reach(sweeps).reset_index().rename(columns={"index": "_rank"})[["joint", "angle_deg", "_rank"]]
    sweeps = (sweeps.merge(rank, on=["joint", "angle_deg"], how="left").sort_values("_rank", kind="stable")
              .drop(columns="_rank").reset_index(drop=True))  # ties between locks go to the one reaching fewest
    least = _least(sweeps)
    value = _value(sweeps)
    by_voxel = [sweeps[c] for c in _VOXEL]
    best = value.groupby(by_voxel, sort=True).idxmax().to_numpy()
    best_kg = _guarantee(value.loc[best].to_numpy())
    reached = np.isfinite(best_kg)
    out = pd.DataFrame({
        "i": least.i, "j": least.j, "k": least.k, "x_m": least.x_m, "y_m": least.y_m, "z_m": least.z_m,
        "tolerant_capacity_kg": _guarantee(least.least_kg.to_numpy()),
        "reachable_every_failure": least.least_kg.to_numpy() >= 0,
        "binding_joint": np.where(reached, least.joint.to_numpy(), -1),
        "binding_angle_deg": np.where(reached, least.angle_deg.to_numpy(), np.nan),
        "tolerant_capacity_double_step_kg": _guarantee(_least(_every_other(sweeps)).least_kg.to_numpy()),
        "healthy_capacity_kg": best_kg,
        "healthy_joint": np.where(reached, sweeps.joint.loc[best].to_numpy(), -1),
        "healthy_angle_deg": np.where(reached, sweeps.angle_deg.loc[best].to_numpy(), np.nan),
        "n_locks": len(locks),
        "n_locks_reaching": (value >= 0).groupby(by_voxel, sort=True).sum().to_numpy().astype(int)})
    for j, part in sweeps.groupby("joint", sort=True):
        out[f"tolerant_j{int(j)}_capacity_kg"] = _guarantee(_least(part).least_kg.to_numpy())
        out[f"tolerant_j{int(j)}_capacity_double_step_kg"] = _guarantee(_least(_every_other(part)).least_kg.to_numpy())
    return out


def scopes(tol: pd.DataFrame) -> list[tuple[str, str, str | None]]:
    """(scope, its column, its column at twice the step or None) of a failure-tolerant table: the healthy arm,
    each joint failing at any angle, any joint."""
    joints = sorted(int(c[len("tolerant_j"):-len("_capacity_kg")]) for c in tol.columns
                    if c.startswith("tolerant_j") and c.endswith("_capacity_kg"))
    return ([("healthy", "healthy_capacity_kg", None)]
            + [(f"joint {j}", f"tolerant_j{j}_capacity_kg", f"tolerant_j{j}_capacity_double_step_kg") for j in joints]
            + [("any joint", "tolerant_capacity_kg", "tolerant_capacity_double_step_kg")])


def tolerance_summary(tol: pd.DataFrame, edge_m: float, payloads_kg) -> pd.DataFrame:
    """:data:`SUMMARY_COLUMNS`, one row per scope (:func:`scopes`) and payload."""
    v = edge_m**3
    rows = []
    for scope, col, coarse_col in scopes(tol):
        c = tol[col].to_numpy()
        coarse = tol[coarse_col].to_numpy() if coarse_col else np.full(len(c), np.nan)
        ok = np.isfinite(c) & np.isfinite(coarse) & (coarse > 0)
        drop = float(np.max((coarse[ok] - c[ok]) / coarse[ok])) if ok.any() else np.nan
        for m in payloads_kg:
            rows.append({"scope": scope, "payload_kg": float(m), "volume_m3": float(np.sum(np.nan_to_num(c, nan=-1) >= m) * v),
                         "volume_double_step_m3": float(np.sum(np.nan_to_num(coarse, nan=-1) >= m) * v)
                         if coarse_col else np.nan,
                         "reachable_m3": float(np.isfinite(c).sum() * v), "double_step_drop_max_rel": drop})
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
