"""Figures of torque-limited following: where the follower's time goes against TOPP-RA's, the torques before and
after limiting, their split into drive terms (no drives: against TOPP-RA's), and a path that cannot be followed."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from capmap.plots.common import legend_beside, not_done_figure, plt, save

__all__ = ["follow_progress", "follow_torques", "follow_torque_split", "follow_infeasible"]

AT_LIMIT = 0.999  # |tau| at or above this fraction of its limit: the joint is at its limit
IDLE = 1e-6  # a joint whose torques stay below this fraction of its limit carries no load on the path
BAND = dict(color="tab:red", alpha=0.12, lw=0)  # the periods a limit is active
LIMIT = dict(color="tab:red", ls=":", lw=1.3)  # a ±limit line
SEGMENT_END = dict(color="0.6", lw=0.8)
STOP = dict(marker="o", mfc="none", mec="tab:orange", mew=1.6, ms=10, ls="none")  # the follower's stop at a waypoint
STYLE = {"cmd": dict(ls="--", color="tab:blue", lw=1.2), "fol": dict(color="black", lw=1.3),
         "opt": dict(ls=":", color="tab:green", lw=1.8)}


def _joint(col: str) -> str:  # 'tau_j2_nm' -> 'joint 2'
    return f"joint {col.split('_')[1][1:]}"


def _cmd(col: str) -> str:
    return col.replace("tau_", "tau_cmd_")


def _pct(x: float) -> str:
    return f"{100 * x:.3g} %"


def _sec(x: float) -> str:  # a duration to 4 significant digits, trailing zeros kept: '70.04 s', '0.8500 s'
    return f"{x:#.4g}".rstrip(".") + " s"


def _dsec(x: float) -> str:  # a signed difference of durations, 3 significant digits: '+10.8 s', '−0.00666 s'
    return f"{x:+#.3g}".rstrip(".").replace("-", "−") + " s"


def _run(ts: pd.DataFrame) -> dict:  # the run's configuration stored with the table (empty when none)
    return ts.attrs.get("capmap", {}).get("config", {}).get("run", {})


def _peak(df: pd.DataFrame, limits: dict, cmd: bool = False) -> tuple[str, float]:
    """The column of the largest |tau| / limit and that ratio (the command's torques with ``cmd``)."""
    return max(((c, float(df[_cmd(c) if cmd else c].abs().max() / limits[c])) for c in limits), key=lambda x: x[1])


def _shade(ax, t: np.ndarray, where: np.ndarray) -> None:  # the periods ``where`` holds, over the full height
    if where.any():
        ax.fill_between(t, 0, 1, where=where, transform=ax.get_xaxis_transform(), step="mid", **BAND)


def _limit_lines(ax, lim: float) -> None:
    for y in (lim, -lim):
        ax.axhline(y, **LIMIT)


def _durations(ts: pd.DataFrame, tp: pd.DataFrame, summary: dict | None) -> tuple[float, float, float]:
    """(follower, TOPP-RA, command) durations; the command's from the summary row, else summed over the segments."""
    t_fol, t_opt = ts.t_s.iloc[-1] - ts.t_s.iloc[0], tp.t_s.iloc[-1] - tp.t_s.iloc[0]
    t_cmd = float((summary or {}).get("command_duration_s", np.nan))
    if not np.isfinite(t_cmd):
        t_cmd = 0.0
        for _, g in ts.groupby("segment"):
            s = g.s_cmd_m.to_numpy()
            t_cmd += g.t_s.iloc[np.flatnonzero(s >= s[-1] - 1e-9 * max(1.0, abs(s[-1])))[0]] - g.t_s.iloc[0]
    return float(t_fol), float(t_opt), t_cmd


def _toppra_note(tp: pd.DataFrame, limits: dict, summary: dict | None) -> str:
    """What TOPP-RA's time-optimal run needs under the follower's full torque model, when that exceeds a limit."""
    col, peak = _peak(tp, limits)
    if peak <= 1.001:
        return ""
    s = summary or {}
    missing = sorted(set(str(s.get("follower_terms", "")).split("+")) - set(str(s.get("toppra_terms", "")).split("+")))
    own = f"its model lacks {' and '.join(missing)} friction; " if missing and s.get("toppra_terms") else ""
    return f"\n({own}with the full model it needs {_pct(peak)} of {_joint(col)}'s limit)"


def follow_progress(ts: pd.DataFrame, tp: pd.DataFrame, limits: dict, case: str, out_png: str | Path,
                    summary: dict | None = None) -> None:
    """Where the follower's time goes: its gap to TOPP-RA split into the S-curve command's part and the torque
    limits' part (title; drawn at the path's end); path speed against v_max, periods a torque limit holds the
    follower back; its lag. ``summary``: the case's summary row (the command's exact duration, the runs' terms)."""
    t = ts.t_s.to_numpy()
    t_fol, t_opt, t_cmd = _durations(ts, tp, summary)
    fig, axes = plt.subplots(3, 1, figsize=(11, 9.6), sharex=True, height_ratios=(1.2, 1, 0.7))
    for ax, (cmd, fol) in zip(axes, (("s_cmd_m", "s_m"), ("sd_cmd_mps", "sd_mps"))):
        ax.plot(t, ts[cmd], **STYLE["cmd"])
        ax.plot(t, ts[fol], **STYLE["fol"])
        ax.plot(tp.t_s, tp[fol], **STYLE["opt"])
    for k, ax in enumerate(axes):
        ax.grid(alpha=0.3)
        _shade(ax, t, ts.limited.to_numpy() & (k > 0))  # the lower panels
    ax, end, t0 = axes[0], float(ts.s_m.iloc[-1]), t[0]
    for y, (a, b), what in ((1.08, (t_opt, t_cmd), "S-curve command − TOPP-RA"), (1.2, (t_cmd, t_fol), "follower − command")):
        ax.annotate("", xy=(t0 + b, y * end), xytext=(t0 + a, y * end),
                    arrowprops=dict(arrowstyle="|-|", color="0.25", lw=1.1, shrinkA=0, shrinkB=0, mutation_scale=2.5))
        ax.text(t0 + min(a, b), y * end, f"{what}: {_dsec(b - a)}  ", ha="right", va="center", fontsize=9)
    ax.set(ylabel="path coordinate s [m]", ylim=(-0.03 * end, 1.3 * end))
    v_key = "follow.ground.v_max_mps" if case == "ground" else "task.v_max_mps"
    v_max = _run(ts).get("follow", {}).get(case, {}).get("v_max_mps", _run(ts).get("task", {}).get("v_max_mps"))
    if v_max is not None:
        axes[1].axhline(v_max, color="0.3", ls="-.", lw=1)
    axes[1].set(ylabel="path speed ds/dt [m/s]", ylim=(0, 1.15 * max(v_max or 0, ts.sd_cmd_mps.max(), tp.sd_mps.max())))
    axes[2].plot(t, 1e3 * ts.lag_m, color="tab:purple", lw=1.3)
    axes[2].set(ylabel="lag s_cmd − s [mm]", xlabel="time t [s]")
    axes[2].set_title(f"the follower's lag behind its command: up to {1e3 * ts.lag_m.max():.3g} mm", fontsize=10)
    col, need = _peak(ts, limits, cmd=True)
    handles = [Line2D([], [], **STYLE["cmd"], label=f"S-curve command, jerk-limited ({_sec(t_cmd)}): ignores the torque "
                      f"limits\n(needs {_pct(need)} of {_joint(col)}'s)"),
               Line2D([], [], **STYLE["fol"], label=f"torque-limited follower ({_sec(t_fol)})"),
               Line2D([], [], **STYLE["opt"], label=f"TOPP-RA: time-optimal under the torque limits, no jerk limit "
                      f"({_sec(t_opt)}){_toppra_note(tp, limits, summary)}"),
               Patch(**BAND, label="a torque limit holds the follower back")]
    handles += [Line2D([], [], color="0.3", ls="-.", lw=1, label=f"speed limit {v_max:g} m/s ({v_key})")] if v_max else []
    fig.legend(handles=handles, loc="upper center", ncol=2, fontsize=8.5, bbox_to_anchor=(0.5, 0.945))
    more = t_fol / t_opt - 1
    fig.suptitle(f"{case}: the follower takes {_pct(abs(more))} {'longer' if more >= 0 else 'less'} than TOPP-RA:\n"
                 f"{_dsec(t_cmd - t_opt)} from its jerk-limited command, {_dsec(t_fol - t_cmd)} from the torque limits",
                 fontsize=12, y=0.995)
    fig.text(0.5, 0.008, f"Off the path: the joint command stays within {1e6 * ts.deviation_m.max():.3g} µm and "
             f"{np.rad2deg(ts.deviation_rad.max()) * 3600:.2g} arcsec of it; the follower yields in time, not in space.",
             ha="center", va="bottom", fontsize=9, color="0.2")
    save(fig, out_png, rect=(0, 0.025, 1, 0.91))


def _loaded(ts: pd.DataFrame, limits: dict) -> tuple[list[str], list[str]]:
    """The limited joints' columns the path loads, and those it does not (|tau| < IDLE x the limit)."""
    idle = [c for c in limits if max(ts[c].abs().max(), ts[_cmd(c)].abs().max() if _cmd(c) in ts else 0) < IDLE * limits[c]]
    return [c for c in limits if c not in idle], idle


def _context(ts: pd.DataFrame, case: str, limits: dict, idle: list[str]) -> str:
    """Where the limits come from (the case's config key; tighter than the capacity map's, said so) and the
    joints not drawn (a locked one, those the path does not load), as title lines."""
    run, out = _run(ts), ""
    given, other = run.get("follow", {}).get(case, {}).get("joint_torque_nm"), run.get("limits", {}).get("joint_torque_nm")
    if given is not None:
        out = f"\nlimits: config follow.{case}.joint_torque_nm = {', '.join(f'{v:g}' for v in np.atleast_1d(given))} N m" + (
            f", tighter than the capacity map's and verification's limits.joint_torque_nm = {np.min(other):g} N m"
            if other is not None and np.max(given) < np.min(other) else "")
    fail = run.get("failure") or {}
    notes = [f"joint {fail['joint']} (locked at {fail['angle_deg']:g}°)"] if f"tau_j{fail.get('joint')}_nm" not in limits \
        and fail else []
    notes += [f"{_joint(c)} (no load on this path)" for c in idle]
    return out + (f"\nnot drawn: {', '.join(notes)}" if notes else "")


def _stops(ts: pd.DataFrame) -> list[tuple[float, float, float]]:
    """The follower's stops at the waypoints: (start, end, top speed m/s) of each brake or approach from a crawl
    (after the segment's top speed, below a thousandth of it) that starts with a jump in the acceleration."""
    out = []
    for _, g in ts.groupby("segment"):
        t, sd, sdd = g.t_s.to_numpy(), g.sd_mps.to_numpy(), g.sdd_mps2.to_numpy()
        k = int(np.argmax(sd)) + 1
        jumps = np.flatnonzero((sd[k:] < 1e-3 * sd.max()) & (sd[k:] > 0) & (np.abs(sdd[k:]) > 4 * np.abs(sdd[k - 1:-1])))
        if len(jumps):
            i = k + jumps[0]
            rest = np.flatnonzero(sd[i + 1:] == 0)
            r = i + rest[0] if len(rest) else len(t) - 1
            end = t[r] + sd[r] / abs(sdd[r]) if len(rest) and sdd[r] else t[r]
            out.append((float(t[i]), float(end), float(sd[i:r + 1].max())))
    return out


def _mark_stops(ax, df: pd.DataFrame, col: str, lim: float, stops: list) -> list:
    """A marker on each stop's torque pulse (its largest |tau|, above 5 % of the limit); its legend entry if any."""
    t, tau, drawn = df.t_s.to_numpy(), df[col].to_numpy(), []
    for a, b, _ in stops:
        w = np.flatnonzero((t >= a) & (t <= b + 1e-9))
        k = w[np.argmax(np.abs(tau[w]))] if len(w) else None
        if k is not None and abs(tau[k]) > 0.05 * lim:
            drawn = ax.plot(t[k], tau[k], **STOP)
    v, d = max([s[2] for s in stops], default=0), max([s[1] - s[0] for s in stops], default=0)
    return [Line2D([], [], **STOP, label=f"the follower's stop at a waypoint: its last ≤ {1e3 * v:.2g} mm/s braked "
                   f"within ≤ {1e3 * d:.2g} ms\n(a torque pulse that short, within the limit)")] if drawn else []


def follow_torques(ts: pd.DataFrame, limits: dict, case: str, out_png: str | Path) -> None:
    """The joints that bind (at their limit, or the command would exceed it) one panel each with their ±limit: the
    command's torque (before limiting) and the follower's (after), shaded where that joint holds the follower back,
    waypoints and stops there marked; the other loaded joints together in % of their limits. Verdict in the title."""
    cols, idle = _loaded(ts, limits)
    ratio = {c: max(ts[c].abs().max(), ts[_cmd(c)].abs().max()) / limits[c] for c in cols}
    bind = [c for c in cols if ratio[c] >= AT_LIMIT] or [max(cols, key=ratio.get)]
    rest = [c for c in cols if c not in bind]
    fig, axes = plt.subplots(len(bind) + bool(rest), 1, figsize=(12, 2.2 + 3.0 * (len(bind) + bool(rest))),
                             sharex=True, squeeze=False)
    t, stops, marked = ts.t_s.to_numpy(), _stops(ts), []
    ends = t[np.flatnonzero(np.diff(ts.segment.to_numpy()))]
    for ax, col in zip(axes[:, 0], bind):
        lim, before, after = limits[col], ts[_cmd(col)].to_numpy(), ts[col].to_numpy()
        _shade(ax, t, ts.limited.to_numpy() & (np.abs(after) >= AT_LIMIT * lim))
        for e in ends:
            ax.axvline(e, **SEGMENT_END)
        ax.plot(t, before, **STYLE["cmd"])
        ax.plot(t, after, color="black", lw=1)
        _limit_lines(ax, lim)
        marked = _mark_stops(ax, ts, col, lim, stops) or marked
        top = 1.25 * max(lim, np.abs(before).max(), np.abs(after).max())
        ax.set(ylim=(-top, top), ylabel="torque [N m]")
        ax.set_title(f"{_joint(col)} (±{lim:g} N m): follower peak {_pct(np.abs(after).max() / lim)}, "
                     f"command {_pct(np.abs(before).max() / lim)}", fontsize=10)
    if rest:
        ax = axes[-1, 0]
        for i, col in enumerate(rest):
            ax.plot(t, 100 * ts[col] / limits[col], color=f"C{i + 2}", lw=1.1, label=f"{_joint(col)} (±{limits[col]:g} N m)")
            ax.plot(t, 100 * ts[_cmd(col)] / limits[col], color=f"C{i + 2}", lw=0.8, ls="--", alpha=0.7)
        _limit_lines(ax, 100.0)
        ax.set(ylim=(-125, 125), ylabel="torque [% of the joint's limit]")
        ax.set_title("the other joints, each in % of its own limit: follower peaks "
                     + ", ".join(f"{_joint(c)} {_pct(ts[c].abs().max() / limits[c])}" for c in rest), fontsize=10)
        legend_beside(ax)
    for ax in axes[:, 0]:
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time t [s]")
    handles = [Line2D([], [], **STYLE["cmd"], label="command, before limiting (jerk-limited: piecewise-linear ramps)"),
               Line2D([], [], color="black", label="follower, after limiting"),
               Line2D([], [], **LIMIT, label="±limit of the joint"), Patch(**BAND, label="this joint holds the follower back")]
    handles += [Line2D([], [], **SEGMENT_END, label="waypoint (segment end, rest to rest)")] if len(ends) else []
    handles += marked
    fig.legend(handles=handles, loc="lower center", ncol=2, fontsize=8.5)
    # the verdict: the follower keeps every limit (to the control period's rounding, 0.1 %); the command's need
    (ja, after), (jb, before) = _peak(ts, limits), _peak(ts, limits, cmd=True)
    kept = (f"keeps every torque limit (peak {_pct(after)} of {_joint(ja)}'s)" if after <= 1.001
            else f"exceeds {_joint(ja)}'s limit: {_pct(after)}")
    need = (f"its command would need {_pct(before)} of {_joint(jb)}'s ({before * limits[jb]:.3g} N m)" if before > 1.0
            else f"the command alone stays within them ({_pct(before)} of {_joint(jb)}'s)")
    fig.suptitle(f"{case}: the follower {kept}; {need}" + _context(ts, case, limits, idle), fontsize=11)
    save(fig, out_png, rect=(0, (0.22 * ((len(handles) + 1) // 2) + 0.25) / fig.get_figheight(), 1, 1))


def follow_torque_split(ts: pd.DataFrame, tp: pd.DataFrame, limits: dict, case: str, terms: str,
                        out_png: str | Path, summary: dict | None = None) -> None:
    """Per loaded joint, over time: the follower's motor torque split into the link dynamics (M q'' + C q' + g),
    the drives' rotor inertia (armature q'') and friction, with the ±limit; ``terms``: the model's terms. A model
    without drive terms ('links') has nothing to split: the follower's torque against TOPP-RA's instead."""
    if terms == "links":
        _against_toppra(ts, tp, limits, case, out_png, summary)
        return
    cols, idle = _loaded(ts, limits)
    rows = (len(cols) + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(12, 1.6 + 3.0 * rows), sharex=True, squeeze=False)
    t, share = ts.t_s.to_numpy(), {}
    for ax, col in zip(axes.ravel(), cols):
        lim, total = limits[col], ts[col].to_numpy()
        arm, fric = ts[col.replace("tau_", "tau_armature_")].to_numpy(), ts[col.replace("tau_", "tau_friction_")].to_numpy()
        links = total - arm - fric
        share[col] = np.abs(arm + fric).max() / lim
        for y, c in ((links, "tab:blue"), (arm, "tab:orange"), (fric, "tab:green")):
            ax.plot(t, y, color=c, lw=1)
        ax.plot(t, total, color="black", lw=1.4)
        _limit_lines(ax, lim)
        top = 1.15 * max(lim, np.abs(total).max(), np.abs(links).max())
        ax.set(ylim=(-top, top), ylabel="torque [N m]")
        ax.set_title(f"{_joint(col)} (±{lim:g} N m): drives up to {_pct(share[col])} of the limit\n(rotor inertia "
                     f"≤ {np.abs(arm).max():.2g} N m, friction ≤ {np.abs(fric).max():.2g} N m)", fontsize=9.5)
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[len(cols):]:
        ax.axis("off")
    for ax in axes.ravel()[max(0, len(cols) - 2):len(cols)]:
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel("time t [s]")
    parts = " + ".join(p for p in terms.split("+") if p in ("coulomb", "viscous")) or "none modelled"
    handles = [Line2D([], [], color=c, label=lab) for c, lab in (("tab:blue", "link dynamics (links, payload)"), (
        "tab:orange", "drives: rotor inertia (armature q̈)"), ("tab:green", f"drives: friction ({parts})"))]
    handles += [Line2D([], [], color="black", lw=1.4, label="motor torque (their sum)"), Line2D([], [], **LIMIT, label="±limit")]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=9)
    j = max(share, key=share.get)
    fig.suptitle(f"{case}: the drives (rotor inertia, friction) take up to {_pct(share[j])} of {_joint(j)}'s torque "
                 f"limit, the rest moves the links" + _context(ts, case, limits, idle), fontsize=11)
    save(fig, out_png, rect=(0, 0.06, 1, 1))


def _at_limit(df: pd.DataFrame, col: str, lim: float) -> float:  # the share of a run's time a joint is at its limit
    t = df.t_s.to_numpy()
    return float(np.diff(t)[np.abs(df[col].to_numpy()[:-1]) >= AT_LIMIT * lim].sum() / (t[-1] - t[0]))


def _against_toppra(ts: pd.DataFrame, tp: pd.DataFrame, limits: dict, case: str, out_png: str | Path,
                    summary: dict | None) -> None:
    """A robot without drives: over time, the torque of the joint most at its limit, the follower's against
    TOPP-RA's (same path, limits, model), with the share of each run's time at the limit."""
    cols, _ = _loaded(ts, limits)
    frac = {c: (_at_limit(ts, c, limits[c]), _at_limit(tp, c, limits[c])) for c in cols}
    col = max(cols, key=lambda c: (max(frac[c]), ts[c].abs().max() / limits[c]))
    lim, (t_fol, t_opt, t_cmd) = limits[col], _durations(ts, tp, summary)
    fig, ax = plt.subplots(figsize=(12, 5.6))
    ax.plot(tp.t_s, tp[col], color="tab:green", lw=1.3)
    ax.plot(ts.t_s, ts[col], color="black", lw=1.1)
    _limit_lines(ax, lim)
    marked = _mark_stops(ax, ts, col, lim, _stops(ts))
    top = 1.25 * max(lim, ts[col].abs().max(), tp[col].abs().max())
    ax.set(ylim=(-top, top), ylabel=f"{_joint(col)} torque [N m]", xlabel="time t [s]")
    ax.grid(alpha=0.3)
    handles = [Line2D([], [], color="tab:green", lw=1.3, label=f"TOPP-RA, time-optimal, no jerk limit ({_sec(t_opt)}): "
                      f"at the limit {_pct(frac[col][1])} of its time"),
               Line2D([], [], color="black", label=f"torque-limited follower of a jerk-limited command ({_sec(t_fol)}): "
                      f"at the limit {_pct(frac[col][0])} of its time"),
               Line2D([], [], **LIMIT, label=f"±limit of the joint ({lim:g} N m)")] + marked
    legend_beside(ax, handles=handles, fontsize=8.5, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
    fig.suptitle(f"{case}, {_joint(col)}: TOPP-RA rides the torque limit, the follower ramps to it with its command")
    fig.text(0.5, 0.01, f"Of the follower's {_dsec(t_fol - t_opt)} over TOPP-RA, its command's jerk limit takes "
             f"{_dsec(t_cmd - t_opt)}, the torque limit {_dsec(t_fol - t_cmd)} (progress.png).\nThis robot file states no "
             "drives: nothing to split, the motor torque is the link dynamics.", ha="center", fontsize=9.5, color="0.2")
    save(fig, out_png, rect=(0, 0.07, 1, 1))


def follow_infeasible(reason: str, shortfall: dict | None, limits: dict, case: str, out_png: str | Path) -> None:
    """A path the arm cannot follow: why (``reason``) and, when a torque cannot be met (``shortfall``: the output,
    the torque needed and its limit, N m), its need in % of the limit on a log axis, the other joints' for scale."""
    def _num(x: float) -> str:  # 3 significant digits, thousands separated: '1,000,000', '71,429', '1.71'
        return f"{x:,.0f}" if x >= 1000 else f"{x:.3g}"

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
