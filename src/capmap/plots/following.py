"""Figures of torque-limited following: progress along the path against TOPP-RA, the torques before
and after limiting, their split into drive terms (or, for a robot without drives, against TOPP-RA's),
and the figure of a path that cannot be followed."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from capmap.plots.common import not_done_figure, plt, save

__all__ = ["follow_progress", "follow_torques", "follow_torque_split", "follow_infeasible"]

AT_LIMIT = 0.999  # |tau| at or above this fraction of its limit: the joint is at its limit
IDLE = 1e-6  # a joint whose torques stay below this fraction of its limit carries no load on the path
BAND = dict(color="tab:red", alpha=0.12, lw=0)  # the periods a limit is active
LIMIT = dict(color="tab:red", ls=":", lw=1.3)  # a ±limit line
SEGMENT_END = dict(color="0.6", lw=0.8)


def _joint(col: str) -> str:
    """'tau_j2_nm' -> 'joint 2'."""
    return f"joint {col.split('_')[1][1:]}"


def _cmd(col: str) -> str:
    return col.replace("tau_", "tau_cmd_")


def _pct(x: float) -> str:
    return f"{100 * x:.3g} %"


def _num(x: float) -> str:
    """A positive number to 3 significant digits, thousands separated: '1,000,000', '71,429', '1.71'."""
    return f"{x:,.0f}" if x >= 1000 else f"{x:.3g}"


def _sec(x: float) -> str:
    """A duration to 3 significant digits, trailing zeros kept: '70.0 s', '0.850 s'."""
    return f"{x:#.3g}".rstrip(".") + " s"


def _shade(ax, t: np.ndarray, where: np.ndarray) -> None:
    """The periods where ``where`` holds as bands over the panel's full height."""
    if where.any():
        ax.fill_between(t, 0, 1, where=where, transform=ax.get_xaxis_transform(), step="mid", **BAND)


def _limit_lines(ax, lim: float) -> None:
    ax.axhline(lim, **LIMIT)
    ax.axhline(-lim, **LIMIT)


def follow_progress(ts: pd.DataFrame, tp: pd.DataFrame, case: str, out_png: str | Path) -> None:
    """The result first: the follower's duration against TOPP-RA's time-optimal one (title, and the gap
    drawn where both reach the path's end); then the path speed with the periods a torque limit is
    active, the follower's lag behind the command and its joint command's deviation from the path."""
    t = ts.t_s.to_numpy()
    t_fol, t_opt, t_cmd = t[-1] - t[0], tp.t_s.iloc[-1] - tp.t_s.iloc[0], _command_duration(ts)
    fig, axes = plt.subplots(4, 1, figsize=(11, 11.5), sharex=True, height_ratios=(1.1, 1, 0.8, 0.8))
    styles = {"cmd": dict(ls="--", color="tab:blue", lw=1.2), "fol": dict(color="black", lw=1.3),
              "opt": dict(ls=":", color="tab:green", lw=1.8)}
    ax = axes[0]
    ax.plot(t, ts.s_cmd_m, **styles["cmd"])
    ax.plot(t, ts.s_m, **styles["fol"])
    ax.plot(tp.t_s, tp.s_m, **styles["opt"])
    end = float(ts.s_m.iloc[-1])
    ax.annotate("", xy=(t[0] + t_fol, 1.06 * end), xytext=(tp.t_s.iloc[0] + t_opt, 1.06 * end),
                arrowprops=dict(arrowstyle="<->", color="0.2", lw=1.2, shrinkA=0, shrinkB=0))
    ax.text(t[0] + 0.5 * (t_fol + t_opt), 1.09 * end, f"{t_fol - t_opt:+#.3g}".rstrip(".") + " s", ha="center",
            va="bottom", fontsize=9)
    ax.set(ylabel="path coordinate s [m]", ylim=(-0.03 * end, 1.25 * end))
    ax = axes[1]
    _shade(ax, t, ts.limited.to_numpy())
    ax.plot(t, ts.sd_cmd_mps, **styles["cmd"])
    ax.plot(t, ts.sd_mps, **styles["fol"])
    ax.plot(tp.t_s, tp.sd_mps, **styles["opt"])
    ax.set(ylabel="path speed ds/dt [m/s]")
    ax = axes[2]
    _shade(ax, t, ts.limited.to_numpy())
    ax.plot(t, 1e3 * ts.lag_m, color="tab:purple", lw=1.3)
    ax.set(ylabel="lag s_cmd − s [mm]")
    ax.set_title(f"the follower's lag behind the command: up to {1e3 * ts.lag_m.max():.3g} mm", fontsize=10)
    _deviation_panel(axes[3], ts)
    for a in axes:
        a.grid(alpha=0.3)
    handles = [Line2D([], [], **styles["cmd"], label=f"S-curve command ({_sec(t_cmd)})"),
               Line2D([], [], **styles["fol"], label=f"torque-limited follower ({_sec(t_fol)})"),
               Line2D([], [], **styles["opt"], label=f"TOPP-RA: time-optimal, no jerk limit ({_sec(t_opt)})"),
               Patch(**BAND, label="a torque limit active (follower held back)")]
    fig.legend(handles=handles, loc="upper center", ncol=2, fontsize=9, bbox_to_anchor=(0.5, 0.97))
    more = t_fol / t_opt - 1
    fig.suptitle(f"{case}: the torque-limited follower needs {_sec(t_fol)}, {abs(100 * more):.3g} % "
                 f"{'more' if more >= 0 else 'less'} than TOPP-RA's time-optimal {_sec(t_opt)}", fontsize=13, y=0.995)
    axes[-1].set_xlabel("time t [s]")
    save(fig, out_png, rect=(0, 0, 1, 0.96))


def _command_duration(ts: pd.DataFrame) -> float:
    """The S-curve command's duration: the first stored time its coordinate is at its final value."""
    s = ts.s_cmd_m.to_numpy()
    done = np.flatnonzero(s >= s[-1] - 1e-9 * max(1.0, abs(s[-1])))
    return float(ts.t_s.iloc[done[0]] - ts.t_s.iloc[0])


def _deviation_panel(ax, ts: pd.DataFrame) -> None:
    """The largest deviation of the joint command from the path in each window (a line, not a block of
    sample-to-sample rounding noise), log scale, against the 1 µm line (below: numerical rounding)."""
    t = ts.t_s.to_numpy()
    window = min(0.5, (t[-1] - t[0]) / 50) or 1.0  # 50 windows or more, none longer than 0.5 s
    t_w, dev_w = _window_max(t, 1e6 * ts.deviation_m.to_numpy(), window)
    peak_um = 1e6 * ts.deviation_m.max()
    ax.semilogy(np.r_[t_w, t[-1]], np.maximum(np.r_[dev_w, dev_w[-1]], 1e-9), color="tab:brown",
                drawstyle="steps-post")
    ax.axhline(1.0, color="0.4", ls=":", lw=1)
    ax.text(t[0], 1.3, "1 µm", color="0.3", fontsize=8, va="bottom")
    ax.set_ylim(1e-6, max(30.0, 10 * peak_um))
    ax.set_ylabel(f"path deviation [µm]\n(largest in each {window:.3g} s)")
    ax.set_title(f"the joint command's deviation from the path: up to {peak_um:.3g} µm, "
                 f"{np.rad2deg(ts.deviation_rad.max()) * 3600:.3g} arcsec"
                 + (" (numerical rounding: the path is kept, only the timing yields)" if peak_um < 1.0 else ""),
                 fontsize=10)


def _window_max(t: np.ndarray, y: np.ndarray, window_s: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Start time and largest value of each ``window_s`` window of a sampled series."""
    idx = np.floor((t - t[0]) / window_s).astype(int)
    starts = np.flatnonzero(np.r_[True, np.diff(idx) > 0])
    return t[starts], np.maximum.reduceat(y, starts)


def _loaded(ts: pd.DataFrame, limits: dict) -> tuple[list[str], list[str]]:
    """The limited joints' columns the path loads, and those it does not (|tau| < IDLE x the limit)."""
    idle = [c for c in limits if max(ts[c].abs().max(), ts[_cmd(c)].abs().max() if _cmd(c) in ts else 0.0)
            < IDLE * limits[c]]
    return [c for c in limits if c not in idle], idle


def _notes(ts: pd.DataFrame, limits: dict, idle: list[str]) -> list[str]:
    """What the panels leave out: a locked joint (the case's failure, not among the limited ones) and the
    joints the path does not load."""
    notes = []
    failure = ts.attrs.get("capmap", {}).get("config", {}).get("run", {}).get("failure")
    if failure and f"tau_j{failure['joint']}_nm" not in limits:
        notes.append(f"joint {failure['joint']} locked at {failure['angle_deg']:g}°")
    if idle:
        notes.append(f"{', '.join(map(_joint, idle))}: no load on this path (|τ| below a millionth of the limit)")
    return [n + ": not drawn" for n in notes]


def _context(ts: pd.DataFrame, limits: dict, idle: list[str]) -> str:
    """The notes of :func:`_notes` as a second title line."""
    notes = _notes(ts, limits, idle)
    return f"\n({'; '.join(notes)})" if notes else ""


def _joint_panels(n: int, row_in: float = 2.7):
    """A figure with one panel per joint, two columns, ``row_in`` inches a row: (fig, axes (rows, 2))."""
    rows = (n + 1) // 2
    return plt.subplots(rows, 2, figsize=(12, 1.0 + row_in * rows), sharex=True, squeeze=False)


def _finish_joint_panels(fig, axes, n: int, handles: list, xlabel: str, title: str, out_png: str | Path) -> None:
    """The legend in the spare panel (an odd number of joints) or under the figure, the x labels, the
    title; saved."""
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    for ax in axes.ravel()[max(0, n - 2):n]:
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel(xlabel)
    if n % 2:
        axes.ravel()[n].legend(handles=handles, loc="center", fontsize=9, frameon=False)
        rect = (0, 0, 1, 1)
    else:
        fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 3), fontsize=9)
        rect = (0, 0.03 + 0.025 * ((len(handles) - 1) // 3), 1, 1)
    fig.suptitle(title)
    save(fig, out_png, rect=rect)


def follow_torques(ts: pd.DataFrame, limits: dict, case: str, out_png: str | Path) -> None:
    """Per loaded joint, on its own scale with its own ±limit: the torque the command would need (before
    limiting) and the follower's (after); shaded where that joint is at its limit and holds the
    follower back; the segment ends (rest at a waypoint) as vertical lines. The verdict in the title:
    whether the follower keeps every limit, and what the unlimited command would need."""
    cols, idle = _loaded(ts, limits)
    fig, axes = _joint_panels(len(cols))
    t = ts.t_s.to_numpy()
    ends = t[np.flatnonzero(np.diff(ts.segment.to_numpy()))]
    for ax, col in zip(axes.ravel(), cols):
        lim, before, after = limits[col], ts[_cmd(col)].to_numpy(), ts[col].to_numpy()
        _shade(ax, t, ts.limited.to_numpy() & (np.abs(after) >= AT_LIMIT * lim))
        for e in ends:
            ax.axvline(e, **SEGMENT_END)
        ax.plot(t, before, "--", color="tab:blue", lw=1)
        ax.plot(t, after, color="black", lw=1)
        _limit_lines(ax, lim)
        top = 1.2 * max(lim, np.abs(before).max(), np.abs(after).max())
        ax.set(ylim=(-top, top), ylabel="torque [N m]")
        ax.set_title(f"{_joint(col)} (±{lim:g} N m): followed peak {_pct(np.abs(after).max() / lim)}, "
                     f"command {_pct(np.abs(before).max() / lim)}", fontsize=10)
        ax.grid(alpha=0.3)
    handles = [Line2D([], [], ls="--", color="tab:blue", label="command, before limiting"),
               Line2D([], [], color="black", label="follower, after limiting"),
               Line2D([], [], **LIMIT, label="±limit of the joint"),
               Patch(**BAND, label="this joint at its limit\n(holding the follower back)")]
    if len(ends):
        handles.append(Line2D([], [], **SEGMENT_END, label="segment end (rest at a waypoint)"))
    _finish_joint_panels(fig, axes, len(cols), handles, "time t [s]",
                         _torque_verdict(ts, limits, case) + _context(ts, limits, idle), out_png)


def _torque_verdict(ts: pd.DataFrame, limits: dict, case: str) -> str:
    """Whether the follower keeps every limit (to the control period's rounding, 0.1 %) and the largest
    torque the command would need, each in % of its joint's limit."""
    after = {c: ts[c].abs().max() / limits[c] for c in limits}
    before = {c: ts[_cmd(c)].abs().max() / limits[c] for c in limits}
    ja, jb = max(after, key=after.get), max(before, key=before.get)
    kept = (f"keeps every torque limit (peak {_pct(after[ja])} of {_joint(ja)}'s)" if after[ja] <= 1.001
            else f"exceeds {_joint(ja)}'s limit: {_pct(after[ja])}")
    need = (f"the command would need {_pct(before[jb])} of {_joint(jb)}'s" if before[jb] > 1.0
            else f"the command alone stays within them ({_pct(before[jb])} of {_joint(jb)}'s)")
    return f"{case}: the follower {kept}; {need}"


def follow_torque_split(ts: pd.DataFrame, tp: pd.DataFrame, limits: dict, case: str, terms: str,
                        out_png: str | Path) -> None:
    """Per loaded joint, along the path: the follower's motor torque split into the link dynamics (links
    and payload: M q'' + C q' + g), the drives' reflected rotor inertia (armature q'') and their friction,
    with the ±limit; ``terms`` names the model's terms (e.g. 'links+armature+coulomb+viscous'). A model
    without drive terms ('links') has nothing to split: the follower's torque against TOPP-RA's instead."""
    if terms == "links":
        _against_toppra(ts, tp, limits, case, out_png)
        return
    cols, idle = _loaded(ts, limits)
    fig, axes = _joint_panels(len(cols), 3.0)
    s = ts.s_m.to_numpy()
    share = {}
    for ax, col in zip(axes.ravel(), cols):
        lim, total = limits[col], ts[col].to_numpy()
        arm, fric = ts[col.replace("tau_", "tau_armature_")].to_numpy(), ts[col.replace("tau_", "tau_friction_")].to_numpy()
        links = total - arm - fric
        share[col] = np.abs(arm + fric).max() / lim
        ax.plot(s, links, color="tab:blue", lw=1)
        ax.plot(s, arm, color="tab:orange", lw=1)
        ax.plot(s, fric, color="tab:green", lw=1)
        ax.plot(s, total, color="black", lw=1.4)
        _limit_lines(ax, lim)
        top = 1.15 * max(lim, np.abs(total).max(), np.abs(links).max())
        ax.set(ylim=(-top, top), ylabel="torque [N m]")
        ax.set_title(f"{_joint(col)} (±{lim:g} N m): drives up to {_pct(share[col])} of the limit\n(rotor inertia "
                     f"≤ {np.abs(arm).max():.2g} N m, friction ≤ {np.abs(fric).max():.2g} N m)", fontsize=9.5)
        ax.grid(alpha=0.3)
    handles = [Line2D([], [], color="tab:blue", label="link dynamics (links, payload)"),
               Line2D([], [], color="tab:orange", label="drives: rotor inertia (armature q̈)"),
               Line2D([], [], color="tab:green", label="drives: friction (" + _friction_terms(terms) + ")"),
               Line2D([], [], color="black", lw=1.4, label="motor torque (their sum)"),
               Line2D([], [], **LIMIT, label="±limit of the joint")]
    j = max(share, key=share.get)
    _finish_joint_panels(fig, axes, len(cols), handles, "path coordinate s [m]",
                         f"{case}: the drives (rotor inertia, friction) take up to {_pct(share[j])} of {_joint(j)}'s "
                         f"torque limit, the rest moves the links\n(model: {terms.replace('+', ' + ')})"
                         + _context(ts, limits, idle).replace("\n", " "), out_png)


def _friction_terms(terms: str) -> str:
    parts = [{"coulomb": "Coulomb", "viscous": "viscous"}[p] for p in terms.split("+") if p in ("coulomb", "viscous")]
    return " + ".join(parts) or "none modelled"


def _time_at_limit(df: pd.DataFrame, col: str, lim: float) -> float:
    """The fraction of a run's duration a joint's torque is at its limit."""
    t = df.t_s.to_numpy()
    at = np.abs(df[col].to_numpy()[:-1]) >= AT_LIMIT * lim
    return float(np.diff(t)[at].sum() / (t[-1] - t[0]))


def _against_toppra(ts: pd.DataFrame, tp: pd.DataFrame, limits: dict, case: str, out_png: str | Path) -> None:
    """A robot without drives (nothing to split): over time, the torque of each joint at its limit in
    either run (else the most loaded joint), the follower's against TOPP-RA's (same path, limits and
    model), with the share of each run's time the joint is at its limit: where the follower's time goes."""
    cols, idle = _loaded(ts, limits)
    frac = {c: (_time_at_limit(ts, c, limits[c]), _time_at_limit(tp, c, limits[c])) for c in cols}
    shown = [c for c in cols if max(frac[c]) > 0] or [max(cols, key=lambda c: ts[c].abs().max() / limits[c])]
    fig, axes = plt.subplots(len(shown), 1, figsize=(12, 2.2 + 3.4 * len(shown)), sharex=True, squeeze=False)
    t_fol, t_opt = ts.t_s.iloc[-1] - ts.t_s.iloc[0], tp.t_s.iloc[-1] - tp.t_s.iloc[0]
    for ax, col in zip(axes[:, 0], shown):
        lim = limits[col]
        ax.plot(tp.t_s, tp[col], color="tab:green", lw=1.3)
        ax.plot(ts.t_s, ts[col], color="black", lw=1.1)
        _limit_lines(ax, lim)
        top = 1.2 * max(lim, ts[col].abs().max(), tp[col].abs().max())
        ax.set(ylim=(-top, top), ylabel="torque [N m]")
        ax.set_title(f"{_joint(col)} (±{lim:g} N m): at its limit {_pct(frac[col][0])} of the follower's "
                     f"{_sec(t_fol)}, {_pct(frac[col][1])} of TOPP-RA's {_sec(t_opt)}", fontsize=10)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time t [s]")
    handles = [Line2D([], [], color="black", label=f"torque-limited follower, jerk-limited ({_sec(t_fol)})"),
               Line2D([], [], color="tab:green", lw=1.3, label=f"TOPP-RA, time-optimal, no jerk limit ({_sec(t_opt)})"),
               Line2D([], [], **LIMIT, label="±limit of the joint")]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=9)
    j = max(shown, key=lambda c: frac[c][1])
    others = "; the other joints never reach their limits (torques.png)" if len(shown) < len(limits) else ""
    fig.suptitle(f"{case}: TOPP-RA holds {_joint(j)} at its limit {_pct(frac[j][1])} of its time, the jerk-limited "
                 f"follower {_pct(frac[j][0])} of its own\n(it ramps its torque and brakes short of the limit): hence its "
                 f"{_pct(t_fol / t_opt - 1)} longer motion\n(no drive terms to split: this robot file states no drives, "
                 f"the motor torque is the link dynamics alone{others})", fontsize=11)
    save(fig, out_png, rect=(0, 0.05, 1, 1))


def follow_infeasible(reason: str, shortfall: dict | None, limits: dict, case: str, out_png: str | Path) -> None:
    """A path the arm cannot follow: why (``reason``) and, when a torque cannot be met (``shortfall``:
    the output, the torque needed and its limit, N m), the joint's need against its limit, in % of the
    limit on a log axis (a need many times the limit stays readable), the other joints' limits for scale."""
    reason = re.sub(r"tau_j(\d+)_nm", r"joint \1", reason)
    if not shortfall:
        not_done_figure(f"{case}: the path cannot be followed under these torque limits", reason, out_png)
        return
    fig, ax = plt.subplots(figsize=(10, 4.6))
    names = list(limits)
    k = names.index(shortfall["output"])
    need = 100 * shortfall["needed_nm"] / shortfall["limit_nm"]
    y = np.arange(len(names))
    ax.barh(y, np.full(len(names), 100.0), color="0.85")
    ax.barh([k], [need], color="tab:red", height=0.5)
    times = _num(need / 100) + " ×"
    ax.text(need, k + 0.35, f"needs {_num(shortfall['needed_nm'])} N m = {times} its limit",
            va="bottom", ha="right", fontsize=9, color="tab:red")
    ax.set_xscale("log")
    ax.set_xlim(1.0, max(1e3, 3 * need))
    ax.axvline(100.0, **LIMIT)
    ax.text(100.0, len(names) - 0.45, " limit (100 %)", color="tab:red", fontsize=8, va="bottom")
    ax.set_ylim(-0.6, len(names) - 0.1)
    ax.set_yticks(y, [f"{_joint(n)} (±{limits[n]:g} N m)" for n in names])
    ax.set_xlabel("torque [% of the joint's limit] (grey: each joint's limit)")
    ax.set_title(f"{case}: cannot be followed: {_joint(shortfall['output'])} needs {times} its limit "
                 f"for {shortfall['what']}", fontsize=11)
    fig.text(0.01, 0.015, reason, fontsize=8.5, va="bottom", ha="left", color="0.2", wrap=True)
    save(fig, out_png, rect=(0, 0.06, 1, 1))
