"""Torque figures of torque-limited following: the torques before and after limiting, their split into drive
terms, and (a robot without drives) the binding joint's torque against TOPP-RA's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from capmap.plots.common import legend_beside, plt, save
from capmap.plots.following import (
    AT_LIMIT,
    BAND,
    LIMIT,
    STYLE,
    _cmd,
    _durations,
    _headline,
    _joint,
    _limit_lines,
    _pct,
    _peak,
    _sec,
    _shade,
)

__all__ = ["follow_torques", "follow_torque_split"]

IDLE = 1e-6  # a joint whose torques stay below this fraction of its limit carries no load on the path
QUIET = 0.1  # a joint whose torques stay below this fraction of its limit is named, not drawn
SEGMENT_END = dict(color="0.6", lw=0.8)
STOP = dict(marker="o", mfc="none", mec="tab:orange", mew=1.6, ms=10, ls="none")  # the follower's stop at a waypoint


def _joints(cols: list[str]) -> str:
    """['tau_j4_nm', 'tau_j5_nm', 'tau_j6_nm'] -> 'joints 4–6'; ['tau_j3_nm', 'tau_j7_nm'] -> 'joints 3, 7'."""
    n = sorted(int(c.split("_")[1][1:]) for c in cols)
    if len(n) == 1:
        return f"joint {n[0]}"
    return f"joints {n[0]}–{n[-1]}" if n == list(range(n[0], n[-1] + 1)) and len(n) > 2 else \
        "joints " + ", ".join(map(str, n))


def _ratio(ts: pd.DataFrame, c: str, lim: float) -> float:  # the largest |tau| / limit, before or after limiting
    return float(max(ts[c].abs().max(), ts[_cmd(c)].abs().max() if _cmd(c) in ts else 0.0) / lim)


def _not_drawn(ts: pd.DataFrame, limits: dict, quiet: list[str]) -> str:
    """'joint 1 locked, joint 7 unloaded, joints 4–6 below 10 %': the joints a figure does not draw, or ''."""
    fail = ts.attrs.get("capmap", {}).get("config", {}).get("run", {}).get("failure") or {}
    words = [f"joint {fail['joint']} locked"] if fail and f"tau_j{fail.get('joint')}_nm" not in limits else []
    idle = [c for c in limits if _ratio(ts, c, limits[c]) < IDLE]
    words += [f"{_joints(idle)} unloaded"] if idle else []
    quiet = [c for c in quiet if c not in idle]
    whose = "their limits" if len(quiet) > 1 else "its limit"
    return ", ".join(words + ([f"{_joints(quiet)} below {_pct(QUIET)} of {whose}"] if quiet else []))


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


def _mark_stops(ax, df: pd.DataFrame, col: str, lim: float, stops: list) -> list[float]:
    """A marker on each stop's torque pulse (its largest |tau|, above 5 % of the limit); those pulses / the limit."""
    t, tau, drawn = df.t_s.to_numpy(), df[col].to_numpy(), []
    for a, b, _ in stops:
        w = np.flatnonzero((t >= a) & (t <= b + 1e-9))
        k = w[np.argmax(np.abs(tau[w]))] if len(w) else None
        if k is not None and abs(tau[k]) > 0.05 * lim:
            drawn.append(abs(tau[k]) / lim)
            ax.plot(t[k], tau[k], **STOP)
    return drawn


def _stop_entry(stops: list, pulses: list[float]) -> list:
    """The stops' one-line legend entry when any is marked: how long the longest braking pulse lasts and whether one
    reaches the limit (``pulses``: the marked pulses / their limits)."""
    d = max([s[1] - s[0] for s in stops], default=0)
    at = "never beyond the limit" if max(pulses, default=0) >= AT_LIMIT else "within the limit"
    return [Line2D([], [], **STOP, label=f"stop at a waypoint: braking pulse ≤ {1e3 * d:.2g} ms, {at}")] if pulses else []


def _limit_note(ts: pd.DataFrame, limits: dict, rated: dict | None, cols: list[str]) -> tuple[str, dict]:
    """Limits tighter than those the arm has elsewhere (``rated``: its rating or the capacity map's limits): when
    all loaded joints share one tightened limit, '; limits 150 N m (tightened for this case)' for the title; else
    per tightened joint ', derated on purpose from 150 N m so the follower must limit it' for its panel (the last
    words when its command exceeds the limit)."""
    tight = {c: rated[c] for c in cols if rated and c in rated and limits[c] < rated[c]}
    if tight and len(tight) == len(cols) and len({limits[c] for c in cols}) == 1:
        return f"; limits {limits[cols[0]]:g} N m (tightened for this case)", {}
    return "", {c: f", derated on purpose from {r:g} N m" + (" so the follower must limit it" if
                ts[_cmd(c)].abs().max() > limits[c] else "") for c, r in tight.items()}


def _bound_panel(ax, ts: pd.DataFrame, col: str, lim: float, ends: np.ndarray) -> None:
    """One binding joint in N m: the command's torque and the follower's, its ±limit, shaded where it holds back."""
    t, before, after = ts.t_s.to_numpy(), ts[_cmd(col)].to_numpy(), ts[col].to_numpy()
    _shade(ax, t, ts.limited.to_numpy() & (np.abs(after) >= AT_LIMIT * lim))
    for e in ends:
        ax.axvline(e, **SEGMENT_END)
    ax.plot(t, before, **STYLE["cmd"])
    ax.plot(t, after, color="black", lw=1)
    _limit_lines(ax, lim)
    top = 1.25 * max(lim, np.abs(before).max(), np.abs(after).max())
    ax.set(ylim=(-top, top), ylabel="torque [N m]")


def _rest_panel(ax, ts: pd.DataFrame, limits: dict, rest: list[str]) -> None:  # the others, each in % of its limit
    for i, col in enumerate(rest):
        ax.plot(ts.t_s, 100 * ts[col] / limits[col], color=f"C{i + 2}", lw=1.1, label=f"{_joint(col)} (±{limits[col]:g} N m)")
        ax.plot(ts.t_s, 100 * ts[_cmd(col)] / limits[col], color=f"C{i + 2}", lw=0.8, ls="--", alpha=0.7)
    _limit_lines(ax, 100.0)
    ax.set(ylim=(-125, 125), ylabel="torque [% of the joint's limit]")
    legend_beside(ax)


def follow_torques(ts: pd.DataFrame, limits: dict, case: str, out_png: str | Path, rated: dict | None = None) -> None:
    """The joints that bind (at their limit, or the command would exceed it) one panel each with their ±limit: the
    command's torque (before limiting) and the follower's (after), shaded where that joint holds the follower back,
    waypoints and stops there marked; the other joints above :data:`QUIET` of their limits together in % of them,
    those below named. The verdict in one line; ``rated``: the arm's limits elsewhere (N m per column), to say
    which limits were tightened for this case."""
    cols = [c for c in limits if _ratio(ts, c, limits[c]) >= IDLE]
    bind = [c for c in cols if _ratio(ts, c, limits[c]) >= AT_LIMIT] or [max(cols, key=lambda c: _ratio(ts, c, limits[c]))]
    rest = [c for c in cols if c not in bind and _ratio(ts, c, limits[c]) >= QUIET]
    fig, axes = plt.subplots(len(bind) + bool(rest), 1, figsize=(12, 1.9 + 3.0 * (len(bind) + bool(rest))),
                             sharex=True, squeeze=False)
    t, stops, marked, (note, derated) = ts.t_s.to_numpy(), _stops(ts), [], _limit_note(ts, limits, rated, cols)
    ends = t[np.flatnonzero(np.diff(ts.segment.to_numpy()))]
    for ax, col in zip(axes[:, 0], bind):
        _bound_panel(ax, ts, col, limits[col], ends)
        marked += _mark_stops(ax, ts, col, limits[col], stops)
        ax.set_title(f"{_joint(col)} (±{limits[col]:g} N m{derated.get(col, '')}): follower peak "
                     f"{_pct(ts[col].abs().max() / limits[col])}, command {_pct(ts[_cmd(col)].abs().max() / limits[col])}",
                     fontsize=10)
    unseen = _not_drawn(ts, limits, [c for c in cols if c not in bind + rest])
    if rest:
        _rest_panel(axes[-1, 0], ts, limits, rest)
        axes[-1, 0].set_title("the other joints, in % of their limits" + (f" (not drawn: {unseen})" if unseen else ""),
                              fontsize=10)
    elif unseen:
        axes[-1, 0].set_title(f"{axes[-1, 0].get_title()}; not drawn: {unseen}", fontsize=10)
    for ax in axes[:, 0]:
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time t [s]")
    handles = [Line2D([], [], **STYLE["cmd"], label="command, before limiting"),
               Line2D([], [], color="black", label="follower, after limiting"),
               Line2D([], [], **LIMIT, label="±limit of the joint"), Patch(**BAND, label="this joint holds the follower back")]
    handles += [Line2D([], [], **SEGMENT_END, label="waypoint (rest to rest)")] if len(ends) else []
    handles += _stop_entry(stops, marked)
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=9)
    (ja, after), (jb, before) = _peak(ts, limits), _peak(ts, limits, cmd=True)  # kept to the period's rounding, 0.1 %
    kept = "keeps every torque limit" if after <= 1.001 else f"exceeds {_joint(ja)}'s limit: {_pct(after)}"
    need = (f"its command would need {_pct(before)} of {_joint(jb)}'s" if before > 1.0
            else "the command alone stays within them")
    _headline(fig, f"{case}: the follower {kept}; {need}{note}")
    save(fig, out_png, rect=(0, (0.22 * ((len(handles) + 2) // 3) + 0.15) / fig.get_figheight(), 1, 1))


def _split_panel(ax, ts: pd.DataFrame, col: str, lim: float) -> float:
    """One joint's motor torque and its terms with the ±limit; the drives' largest share of the limit."""
    t, total = ts.t_s.to_numpy(), ts[col].to_numpy()
    arm, fric = ts[col.replace("tau_", "tau_armature_")].to_numpy(), ts[col.replace("tau_", "tau_friction_")].to_numpy()
    links = total - arm - fric
    for y, c in ((links, "tab:blue"), (arm, "tab:orange"), (fric, "tab:green")):
        ax.plot(t, y, color=c, lw=1)
    ax.plot(t, total, color="black", lw=1.4)
    _limit_lines(ax, lim)
    top = 1.15 * max(lim, np.abs(total).max(), np.abs(links).max())
    share = float(np.abs(arm + fric).max() / lim)
    ax.set(ylim=(-top, top), ylabel="torque [N m]")
    ax.set_title(f"{_joint(col)} (±{lim:g} N m): drives up to {_pct(share)}", fontsize=10)
    ax.grid(alpha=0.3)
    return share


def follow_torque_split(ts: pd.DataFrame, tp: pd.DataFrame, limits: dict, case: str, terms: str,
                        out_png: str | Path, summary: dict | None = None) -> None:
    """Per joint above :data:`QUIET` of its limit, over time: the follower's motor torque split into the link
    dynamics (M q'' + C q' + g), the drives' rotor inertia (armature q'') and friction, with the ±limit; the other
    joints named in one line; ``terms``: the model's terms. A model without drive terms ('links') has nothing to
    split: the binding joint's torque, the follower's against TOPP-RA's, instead."""
    if terms == "links":
        _against_toppra(ts, tp, limits, case, out_png, summary)
        return
    cols = [c for c in limits if _ratio(ts, c, limits[c]) >= IDLE]
    fric = lambda c: ts[c.replace("tau_", "tau_armature_")] + ts[c.replace("tau_", "tau_friction_")]  # noqa: E731
    shown = [c for c in cols if max(ts[c].abs().max(), fric(c).abs().max()) >= QUIET * limits[c]] or cols
    ncol = min(len(shown), 3 if len(shown) % 3 == 0 else 2)
    rows = -(-len(shown) // ncol)
    fig, axes = plt.subplots(rows, ncol, figsize=(12, 1.8 + 3.2 * rows), sharex=True, squeeze=False)
    share = {col: _split_panel(ax, ts, col, limits[col]) for ax, col in zip(axes.ravel(), shown)}
    for ax in axes.ravel()[len(shown):]:
        ax.axis("off")
    for ax in axes.ravel()[max(0, len(shown) - ncol):len(shown)]:  # the lowest panel of each column
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel("time t [s]")
    parts = " + ".join({"coulomb": "Coulomb", "viscous": "viscous"}[p] for p in terms.split("+")
                       if p in ("coulomb", "viscous")) or "none modelled"
    handles = [Line2D([], [], color=c, label=lab) for c, lab in (("tab:blue", "link dynamics (links, payload)"), (
        "tab:orange", "drives: rotor inertia"), ("tab:green", f"drives: friction ({parts})"))]
    handles += [Line2D([], [], color="black", lw=1.4, label="motor torque (their sum)"), Line2D([], [], **LIMIT, label="±limit")]
    unseen = _not_drawn(ts, limits, [c for c in cols if c not in shown])
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=9, bbox_to_anchor=(0.5, 0.04 if unseen else 0.0))
    if unseen:
        fig.text(0.5, 0.01, f"not drawn: {unseen}", ha="center", fontsize=9.5, color="0.2")
    j = max(share, key=share.get)
    _headline(fig, f"{case}: the drives (rotor inertia, friction) take up to {_pct(share[j])} of {_joint(j)}'s torque "
              "limit, the rest moves the links")
    save(fig, out_png, rect=(0, (0.45 + 0.3 * bool(unseen)) / fig.get_figheight(), 1, 1))


def _at_limit(df: pd.DataFrame, col: str, lim: float) -> float:  # the share of a run's time a joint is at its limit
    t = df.t_s.to_numpy()
    return float(np.diff(t)[np.abs(df[col].to_numpy()[:-1]) >= AT_LIMIT * lim].sum() / (t[-1] - t[0]))


def _against_toppra(ts: pd.DataFrame, tp: pd.DataFrame, limits: dict, case: str, out_png: str | Path,
                    summary: dict | None) -> None:
    """A robot without drives: over time, the torque of the joint most at its limit, the follower's against
    TOPP-RA's (same path, limits, model); the share of each run's time at the limit in the title."""
    cols = [c for c in limits if _ratio(ts, c, limits[c]) >= IDLE]
    frac = {c: (_at_limit(ts, c, limits[c]), _at_limit(tp, c, limits[c])) for c in cols}
    col = max(cols, key=lambda c: (max(frac[c]), ts[c].abs().max() / limits[c]))
    lim, (t_fol, t_opt, _) = limits[col], _durations(ts, tp, summary)
    fig, ax = plt.subplots(figsize=(12, 5.2))
    ax.plot(tp.t_s, tp[col], color="tab:green", lw=1.3)
    ax.plot(ts.t_s, ts[col], color="black", lw=1.1)
    _limit_lines(ax, lim)
    stops = _stops(ts)
    marked = _stop_entry(stops, _mark_stops(ax, ts, col, lim, stops))
    top = 1.25 * max(lim, ts[col].abs().max(), tp[col].abs().max())
    ax.set(ylim=(-top, top), ylabel=f"{_joint(col)} torque [N m]", xlabel="time t [s]")
    ax.grid(alpha=0.3)
    handles = [Line2D([], [], color="tab:green", lw=1.3, label=f"TOPP-RA, time-optimal ({_sec(t_opt)})"),
               Line2D([], [], color="black", label=f"follower of a jerk-limited command ({_sec(t_fol)})"),
               Line2D([], [], **LIMIT, label=f"±limit ({lim:g} N m)")] + marked
    legend_beside(ax, handles=handles, fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
    _headline(fig, f"{case}, {_joint(col)}: TOPP-RA rides its torque limit {_pct(frac[col][1])} of the time, the follower "
              f"{_pct(frac[col][0])}: it ramps up with its jerk-limited command")
    save(fig, out_png)
