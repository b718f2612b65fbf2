"""A whole path followed segment by segment, each also solved by TOPP-RA on the same path and
limits, and the family's tables of it (column schemas, units in the names): the follower's time
series, TOPP-RA's, and the comparison row."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, fields, replace
from typing import Callable

import numpy as np
import pandas as pd

from capmap.core.reduction import LockedArm
from capmap.errors import LimitInfeasible, SolverFailed, TrackingLost
from capmap.following.comparison import FollowComparison, compare, model_terms
from capmap.following.follower import FollowSettings, follow_segment
from capmap.following.path_dynamics import Shortfall
from capmap.following.toppra_reference import ToppraSettings, time_optimal

__all__ = ["PathRun", "follow_path", "follow_tables", "stored_rows", "summary_row", "run_lines"]

# what makes a path infeasible (a result, written as such): limits that cannot be met, a follower or TOPP-RA
# that does not arrive, a segment the arm cannot track
INFEASIBLE = (LimitInfeasible, SolverFailed, TrackingLost)


@dataclass(frozen=True)
class PathRun:
    """The followed segments and TOPP-RA's solutions on them (one each per segment), and their
    comparison over the whole path; when the path cannot be followed, the segments before the one
    that fails, ``reason`` (why, with the segment) and ``shortfall`` (the torque that cannot be met,
    when that is why), and no comparison. ``terms``: the torque model's terms."""

    followed: list
    optimal: list
    comparison: FollowComparison | None
    terms: str
    reason: str = ""
    shortfall: Shortfall | None = None

    @property
    def feasible(self) -> bool:
        return not self.reason


def follow_path(arm: LockedArm, waypoints: np.ndarray, rotation: np.ndarray, q_start: np.ndarray,
                settings: FollowSettings, progress: Callable[[str], None] = lambda _: None) -> PathRun:
    """Follow waypoints (W, 3) m as straight segments at ``rotation`` (3, 3) from q_start
    (n_active,) rad, each segment continuing from the last one's final configuration."""
    limits = settings.torque_limits(arm)
    followed, optimal, no_viscous = [], [], []
    viscous = bool(np.any(arm.robot.viscous_nms[arm.active] > 0))
    arm_nv = _without_viscous(arm) if viscous else None
    q, terms = q_start, model_terms(arm)
    for k in range(len(waypoints) - 1):
        t0 = time.perf_counter()
        try:
            seg = follow_segment(arm, waypoints[k], waypoints[k + 1], rotation, q, settings)
            el = time.perf_counter() - t0
            top = time_optimal(arm, seg.table, settings.payload_kg, limits,
                               ToppraSettings(settings.v_max_mps, settings.a_max_mps2, sample_dt_s=settings.period_s))
            if viscous:  # the model TOPP-RA has: like for like
                no_viscous.append(follow_segment(arm_nv, waypoints[k], waypoints[k + 1], rotation, q, settings))
        except INFEASIBLE as exc:
            reason = f"segment {k + 1} of {len(waypoints) - 1}: {exc}"
            progress(f"infeasible: {reason}")
            return PathRun(followed, optimal, None, terms, reason, getattr(exc, "shortfall", None))
        r = seg.result
        followed.append(seg)
        optimal.append(top)
        progress(f"segment {k + 1}/{len(waypoints) - 1}: {seg.table.length_m:.3f} m, command {seg.command.duration_s:.3f} s, "
                 f"follower {r.duration_s:.3f} s ({int(r.limited.sum())} of {len(r.t_s)} periods limited), "
                 f"TOPP-RA {top.duration_s:.3f} s; {el:.2f} s wall incl. path preparation and exact evaluation")
        q = seg.q[-1]
    return PathRun(followed, optimal, compare(followed, optimal, limits, arm, no_viscous or None), terms)


def _without_viscous(arm: LockedArm) -> LockedArm:
    """The same arm with its drives' viscous friction set to zero (models copied: the robot's stay as they are)."""
    robot = arm.robot
    model, model_ng = robot.model.copy(), robot.model_no_gravity.copy()
    model.damping[:] = 0.0
    model_ng.damping[:] = 0.0
    return replace(arm, robot=replace(robot, model=model, model_no_gravity=model_ng))


def follow_tables(case: str, arm: LockedArm, run: PathRun) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The follower's time series (one row per control period: command, state, lag, torques,
    joints, deviation) and TOPP-RA's (its samples and torques), on path and time axes running on
    across segments. Time, path coordinate, speed and acceleration are stored in float64; torques, joint
    angles, lag and deviation in float32 (7 significant digits, for plots and reading: the summary's
    figures come from the full-precision values), every control period kept (:func:`stored_rows` thins it)."""
    joints = arm.active_joint_numbers
    if not run.followed:  # infeasible from the first segment: the tables' columns, no rows
        return _empty_series(case, joints)
    parts, tparts = [], []
    t_off = t_off_topp = s_off = 0.0
    for k, (seg, top) in enumerate(zip(run.followed, run.optimal)):
        r = seg.result
        df = pd.DataFrame({"case": case, "segment": k, "t_s": t_off + r.t_s, "s_cmd_m": s_off + r.s_cmd,
                           "sd_cmd_mps": r.sd_cmd, "sdd_cmd_mps2": r.sdd_cmd, "s_m": s_off + r.s, "sd_mps": r.sd,
                           "sdd_mps2": r.sdd, "lag_m": r.s_cmd - r.s, "limited": r.limited,
                           "infeasible": r.infeasible})
        for prefix, values in (("tau_cmd", seg.tau_cmd), ("tau", seg.tau), ("tau_armature", seg.tau_armature),
                               ("tau_friction", seg.tau_friction)):
            for c, jn in enumerate(joints):
                df[f"{prefix}_j{jn}_nm"] = values[:, c]
        for c, jn in enumerate(joints):
            df[f"q_j{jn}_deg"] = np.rad2deg(seg.q[:, c])
        df["deviation_m"] = seg.deviation_m
        df["deviation_rad"] = seg.deviation_rad
        parts.append(_compact(df))
        tdf = pd.DataFrame({"case": case, "segment": k, "t_s": t_off_topp + top.t_s, "s_m": s_off + top.s,
                            "sd_mps": top.sd})
        for c, jn in enumerate(joints):
            tdf[f"tau_j{jn}_nm"] = top.tau[:, c]
        tparts.append(_compact(tdf))
        t_off += r.duration_s
        t_off_topp += top.duration_s
        s_off += seg.table.length_m
    return pd.concat(parts, ignore_index=True), pd.concat(tparts, ignore_index=True)


def _empty_series(case: str, joints) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The follower's and TOPP-RA's time series with their columns and no rows."""
    tau = [f"{p}_j{j}_nm" for p in ("tau_cmd", "tau", "tau_armature", "tau_friction") for j in joints]
    ts = pd.DataFrame({"case": pd.Series(dtype=str), "segment": pd.Series(dtype=int),
                       **{c: pd.Series(dtype=float) for c in _EXACT + ("lag_m",)},
                       "limited": pd.Series(dtype=bool), "infeasible": pd.Series(dtype=bool),
                       **{c: pd.Series(dtype=np.float32) for c in tau + [f"q_j{j}_deg" for j in joints]
                          + ["deviation_m", "deviation_rad"]}})
    tp = pd.DataFrame({"case": pd.Series(dtype=str), "segment": pd.Series(dtype=int),
                       **{c: pd.Series(dtype=float) for c in ("t_s", "s_m", "sd_mps")},
                       **{f"tau_j{j}_nm": pd.Series(dtype=np.float32) for j in joints}})
    return ts, tp


def stored_rows(ts: pd.DataFrame, every: int, limit_nm: np.ndarray) -> pd.DataFrame:
    """The rows of a follower's (or TOPP-RA's) time series (one per control period) kept for storage: in each segment
    every ``every``-th row and its last, the rows where ``limited`` or ``infeasible`` changes, and in
    each window of ``every`` rows the row of the largest torque in proportion to ``limit_nm``
    (n_active,) N m (the ``tau_j*_nm`` columns, in order), so that a plot of the stored series reaches
    every window's torque peak. ``every`` <= 1 keeps every row."""
    if every <= 1 or ts.empty:
        return ts
    seg = ts["segment"].to_numpy()
    n = len(ts)
    first = np.r_[True, seg[1:] != seg[:-1]]
    last = np.r_[seg[1:] != seg[:-1], True]
    starts = np.flatnonzero(first)
    pos = np.arange(n) - np.repeat(starts, np.diff(np.r_[starts, n]))
    window = np.cumsum(pos % every == 0) - 1
    tau = ts[[c for c in ts.columns if c.startswith("tau_j")]].to_numpy(dtype=float)
    ratio = np.abs(tau / np.asarray(limit_nm, dtype=float)).max(axis=1)
    keep = (pos % every == 0) | last
    order = np.lexsort((-ratio, window))  # by window, the largest ratio first
    keep[order[np.r_[True, window[order][1:] != window[order][:-1]]]] = True
    for flag in ("limited", "infeasible"):  # the follower's flags (TOPP-RA's series has none)
        if flag not in ts:
            continue
        f = ts[flag].to_numpy()
        keep[1:] |= (f[1:] != f[:-1]) & ~first[1:]
        keep[:-1] |= (f[1:] != f[:-1]) & ~first[1:]
    return ts[keep].reset_index(drop=True)


_EXACT = ("t_s", "s_cmd_m", "sd_cmd_mps", "sdd_cmd_mps2", "s_m", "sd_mps", "sdd_mps2")


def _compact(df: pd.DataFrame) -> pd.DataFrame:
    """The float columns not in _EXACT as float32 (halves a 1 ms series' size)."""
    cols = [c for c in df.columns if df[c].dtype == np.float64 and c not in _EXACT]
    return df.astype({c: np.float32 for c in cols})


def summary_row(case: str, arm: LockedArm, label: str, settings: FollowSettings, run: PathRun) -> pd.DataFrame:
    """The comparison as the summary table's one row: ``feasible`` and, when not, ``reason`` (the
    comparison's figures NaN)."""
    figures = asdict(run.comparison) if run.comparison is not None else \
        {f.name: np.nan for f in fields(FollowComparison)} | {"follower_terms": run.terms}
    return pd.DataFrame([{"case": case, "robot": arm.robot.name, "path": label, "payload_kg": settings.payload_kg,
                          "feasible": run.feasible, "reason": run.reason, **figures, "period_s": settings.period_s}])


def run_lines(run: PathRun) -> list[str]:
    """What a followed path came to, in a few log lines."""
    if not run.feasible:
        return [f"infeasible ({run.terms}): {run.reason}"]
    cmp = run.comparison
    lines = [f"{cmp.length_m:.3f} m in {cmp.follower_duration_s:.3f} s vs TOPP-RA {cmp.toppra_duration_s:.3f} s "
             f"(ratio {cmp.duration_ratio:.3f}); peak torque {cmp.follower_peak_torque_pct:.3f}% of limit "
             f"(TOPP-RA {cmp.toppra_peak_torque_pct:.3f}%); command would need {cmp.command_peak_torque_pct:.1f}%; "
             f"max path deviation {cmp.max_deviation_m:.2e} m; torque model {cmp.follower_terms}"]
    if cmp.follower_terms != cmp.toppra_terms:
        lines.append(f"TOPP-RA ({cmp.toppra_terms}, no viscous friction) peaks at {cmp.toppra_peak_torque_pct:.1f}% of "
                     f"the limit with it; the follower without viscous friction (like for like): "
                     f"{cmp.follower_no_viscous_duration_s:.3f} s, ratio {cmp.duration_ratio_no_viscous:.3f}")
    return lines
