"""Figures of torque-limited following: where the follower's time goes against TOPP-RA's (progress) and a path
that cannot be followed; the shared styles and number formats of the following figures (the torque figures:
:mod:`capmap.plots.following_limits`)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from capmap.plots.common import not_done_figure, plt, save

__all__ = ["follow_progress", "follow_infeasible"]

AT_LIMIT = 0.999  # |tau| at or above this fraction of its limit: the joint is at its limit
BAND = dict(color="tab:red", alpha=0.12, lw=0)  # the periods a limit is active
LIMIT = dict(color="tab:red", ls=":", lw=1.3)  # a ±limit line
STYLE = {"cmd": dict(ls="--", color="tab:blue", lw=1.2), "fol": dict(color="black", lw=1.3),
         "opt": dict(ls=":", color="tab:green", lw=1.8)}
MOSTLY = 0.9  # one part of the follower's gap to TOPP-RA at least this share of it: 'almost all' of it
ON_PATH_M, ON_PATH_RAD = 1e-4, 1e-4  # the command within these of the path: it stays on it


def _joint(col: str) -> str:  # 'tau_j2_nm' -> 'joint 2'
    return f"joint {col.split('_')[1][1:]}"


def _cmd(col: str) -> str:
    return col.replace("tau_", "tau_cmd_")


def _num(v: float) -> str:  # what a reader needs: whole numbers from 10 on, else 2 significant digits ('6.6', '0.03')
    return f"{v:.0f}" if abs(v) >= 10 else f"{v:.2g}"


def _pct(x: float) -> str:  # a fraction in %: '18 %', '6.6 %', '130 %'
    return f"{_num(100 * x)} %"


def _sec(x: float) -> str:  # a duration: '70.1 s', '0.91 s', '0.03 s'
    return (f"{x:.1f}" if abs(x) >= 1 else f"{x:.2g}").replace("-", "−") + " s"


def _headline(fig, text: str, size: float = 12, **kw) -> None:
    """The figure's one-line verdict, its font shrunk (to 10 pt at least) when the line would be wider than the figure."""
    title = fig.suptitle(text, fontsize=size, **kw)
    width = title.get_window_extent(fig.canvas.get_renderer()).width
    if width > 0.97 * fig.bbox.width:
        title.set_fontsize(max(10.0, size * 0.97 * fig.bbox.width / width))


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


def _toppra_beyond(tp: pd.DataFrame, limits: dict, summary: dict | None) -> str:
    """', which ignores viscous friction and would need 115 % of joint 1's limit': when TOPP-RA's time-optimal run
    exceeds a limit under the follower's full torque model (naming the terms its own model lacks); else ''."""
    col, peak = _peak(tp, limits)
    if peak <= 1.001:
        return ""
    s = summary or {}
    missing = sorted(set(str(s.get("follower_terms", "")).split("+")) - set(str(s.get("toppra_terms", "")).split("+")))
    own = f"ignores {' and '.join(missing)} friction and " if missing and s.get("toppra_terms") else ""
    return f", which {own}would need {_pct(peak)} of {_joint(col)}'s limit"


def _what(case: str, ts: pd.DataFrame, summary: dict | None) -> str:
    """'space, 1500 kg on the planned path': the case, its payload and path (those the summary row or table give)."""
    s = summary or {}
    kg = s.get("payload_kg", ts.attrs.get("capmap", {}).get("payload_kg"))
    kg = f"{float(kg):g} kg" if kg is not None and np.isfinite(float(kg)) else ""
    path = f"the {s['path']}" if isinstance(s.get("path"), str) else ""
    return ", ".join(filter(None, (case, " on ".join(filter(None, (kg, path))))))


def _gap(ax, t0: float, end: float, t: tuple[float, float, float]) -> str:
    """The follower's gap to TOPP-RA split into its jerk-limited command's part and the torque limits': brackets at
    the path's end when both parts add time (then how they share it, for the title), else in words over the panel."""
    t_fol, t_opt, t_cmd = t
    a, b = t_cmd - t_opt, t_fol - t_cmd
    if a <= 0 or b <= 0:
        cmd = (f"its command alone would finish {_sec(-a)} before TOPP-RA (it ignores the torque limits)" if a <= 0
               else f"its jerk-limited command adds {_sec(a)}")
        lim = f"the torque limits add {_sec(b)}" if b > 0 else f"it then finishes {_sec(-b)} before its command"
        ax.set_title(f"{cmd}; {lim}", fontsize=10)
        return ""
    for y, (u, v), what in ((1.08, (t_opt, t_cmd), "jerk limit"), (1.2, (t_cmd, t_fol), "torque limits")):
        ax.annotate("", xy=(t0 + v, y * end), xytext=(t0 + u, y * end),
                    arrowprops=dict(arrowstyle="|-|", color="0.25", lw=1.1, shrinkA=0, shrinkB=0, mutation_scale=2.5))
        ax.text(t0 + u, y * end, f"{what}: +{_sec(v - u)}  ", ha="right", va="center", fontsize=9)
    if a >= MOSTLY * (a + b) or b >= MOSTLY * (a + b):
        return f", almost all from {'its jerk limit' if a > b else 'the torque limits'}"
    return f": {_sec(a)} from its jerk limit, {_sec(b)} from the torque limits"


def _lag_title(ts: pd.DataFrame) -> str:  # the lag (along the path) and whether the command stays on the path
    off = ts.deviation_m.max() > ON_PATH_M or ts.deviation_rad.max() > ON_PATH_RAD
    lag = _num(1e3 * ts.lag_m.max())
    return f"the follower's lag behind its command: up to {lag} mm along the path" + (
        f"; off it by up to {_num(1e3 * ts.deviation_m.max())} mm" if off else ", never off it")


def follow_progress(ts: pd.DataFrame, tp: pd.DataFrame, limits: dict, case: str, out_png: str | Path,
                    summary: dict | None = None) -> None:
    """Where the follower's time goes: the verdict against TOPP-RA in one line (the case's payload and path, both
    durations, and what the gap comes from, or that TOPP-RA itself exceeds a limit under the full torque model);
    path coordinate with the gap's split at the path's end; path speed against v_max, periods a torque limit holds
    the follower back; its lag. ``summary``: the case's summary row (path, payload, the command's exact duration)."""
    t = ts.t_s.to_numpy()
    t_fol, t_opt, t_cmd = _durations(ts, tp, summary)
    fig, axes = plt.subplots(3, 1, figsize=(12, 9.2), sharex=True, height_ratios=(1.2, 1, 0.7))
    for ax, (cmd, fol) in zip(axes, (("s_cmd_m", "s_m"), ("sd_cmd_mps", "sd_mps"))):
        ax.plot(t, ts[cmd], **STYLE["cmd"])
        ax.plot(t, ts[fol], **STYLE["fol"])
        ax.plot(tp.t_s, tp[fol], **STYLE["opt"])
    for k, ax in enumerate(axes):
        ax.grid(alpha=0.3)
        _shade(ax, t, ts.limited.to_numpy() & (k > 0))  # the lower panels
    end = float(ts.s_m.iloc[-1])
    share = _gap(axes[0], t[0], end, (t_fol, t_opt, t_cmd))
    axes[0].set(ylabel="path coordinate s [m]", ylim=(-0.03 * end, 1.3 * end))
    run = ts.attrs.get("capmap", {}).get("config", {}).get("run", {})
    v_max = run.get("follow", {}).get(case, {}).get("v_max_mps", run.get("task", {}).get("v_max_mps"))
    if v_max is not None:
        axes[1].axhline(v_max, color="0.3", ls="-.", lw=1)
    axes[1].set(ylabel="path speed ds/dt [m/s]", ylim=(0, 1.15 * max(v_max or 0, ts.sd_cmd_mps.max(), tp.sd_mps.max())))
    axes[2].plot(t, 1e3 * ts.lag_m, color="tab:purple", lw=1.3)
    axes[2].set(ylabel="lag s_cmd − s [mm]", xlabel="time t [s]")
    axes[2].set_title(_lag_title(ts), fontsize=10)
    col, need = _peak(ts, limits, cmd=True)
    handles = [Line2D([], [], **STYLE["cmd"], label=f"S-curve command, jerk-limited ({_sec(t_cmd)}): needs {_pct(need)} "
                      f"of {_joint(col)}'s limit"),
               Line2D([], [], **STYLE["fol"], label=f"torque-limited follower ({_sec(t_fol)})"),
               Line2D([], [], **STYLE["opt"], label=f"TOPP-RA: time-optimal, no jerk limit ({_sec(t_opt)})"),
               Patch(**BAND, label="a torque limit holds the follower back")]
    handles += [Line2D([], [], color="0.3", ls="-.", lw=1, label=f"speed limit {v_max:g} m/s")] if v_max else []
    fig.legend(handles=handles, loc="upper center", ncol=2, fontsize=9, bbox_to_anchor=(0.5, 0.96))
    more, beyond = t_fol / t_opt - 1, _toppra_beyond(tp, limits, summary)
    _headline(fig, f"{_what(case, ts, summary)}: follower {_sec(t_fol)}, {_pct(abs(more))} "
              f"{'longer' if more >= 0 else 'shorter'} than TOPP-RA ({_sec(t_opt)})" + (beyond or share), y=0.995)
    save(fig, out_png, rect=(0, 0, 1, 0.905))


def follow_infeasible(reason: str, shortfall: dict | None, limits: dict, case: str, out_png: str | Path) -> None:
    """A path the arm cannot follow: why (``reason``) and, when a torque cannot be met (``shortfall``: the output,
    the torque needed and its limit, N m), its need in % of the limit on a log axis, the other joints' for scale."""
    def _big(x: float) -> str:  # 3 significant digits, thousands separated: '1,000,000', '71,429', '1.71'
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
    times = _big(need / 100) + " ×"
    ax.text(need, k + 0.35, f"needs {_big(shortfall['needed_nm'])} N m = {times} its limit",
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
