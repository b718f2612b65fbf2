"""Figures of torque-limited following: progress along the path and torques before/after limiting."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import plt, save

__all__ = ["follow_progress", "follow_torques", "follow_torque_split"]


def follow_progress(ts: pd.DataFrame, tp: pd.DataFrame, case: str, out_png: str | Path) -> None:
    """Path coordinate and speed: command, torque-limited follower, TOPP-RA; lag; path deviation."""
    fig, axes = plt.subplots(4, 1, figsize=(11, 11), sharex=True)
    ax = axes[0]
    ax.plot(ts.t_s, ts.s_cmd_m, "--", color="tab:blue", lw=1.2, label="command s (S-curve)")
    ax.plot(ts.t_s, ts.s_m, color="black", lw=1.2, label="followed s")
    ax.plot(tp.t_s, tp.s_m, ":", color="tab:green", lw=1.2, label="TOPP-RA (time-optimal, no jerk limit)")
    ax.set(ylabel="path coordinate s [m]", title=f"{case}: progress along the path")
    ax.legend(fontsize=8)
    ax = axes[1]
    ax.plot(ts.t_s, ts.sd_cmd_mps, "--", color="tab:blue", lw=1.2, label="command")
    ax.plot(ts.t_s, ts.sd_mps, color="black", lw=1.2, label="followed")
    ax.plot(tp.t_s, tp.sd_mps, ":", color="tab:green", lw=1.2, label="TOPP-RA")
    lim = ts.limited.to_numpy()
    if lim.any():
        ax.fill_between(ts.t_s, 0, ts.sd_mps.max() * 1.05, where=lim, color="tab:red", alpha=0.12, step="mid",
                        label="torque limit active")
    ax.set(ylabel="path speed ds/dt [m/s]")
    ax.legend(fontsize=8)
    axes[2].plot(ts.t_s, 1e3 * ts.lag_m, color="tab:purple")
    axes[2].set(ylabel="lag s_cmd - s [mm]", title="lag of the follower behind the command")
    # deviation: the largest value in each window (a line, not a block of sample-to-sample rounding noise)
    t = ts.t_s.to_numpy()
    window = min(0.5, (t[-1] - t[0]) / 50) or 1.0  # 50 windows or more, none longer than 0.5 s
    t_w, dev_w = _window_max(t, 1e6 * ts.deviation_m.to_numpy(), window)
    peak_um = 1e6 * ts.deviation_m.max()
    axes[3].semilogy(np.r_[t_w, t[-1]], np.maximum(np.r_[dev_w, dev_w[-1]], 1e-9), color="tab:brown",
                     drawstyle="steps-post", label=f"largest deviation in each {window:.3g} s")
    axes[3].axhline(1.0, color="0.4", ls=":", lw=1)
    axes[3].set_ylim(1e-6, max(10.0, 3 * peak_um))
    axes[3].legend(fontsize=8, loc="lower left")
    axes[3].set(ylabel="path deviation [um]", xlabel="time t [s]",
                title=f"deviation of the joint command from the path: max {peak_um:.3g} um, "
                      f"{np.rad2deg(ts.deviation_rad.max()) * 3600:.3g} arcsec"
                      + (" (numerical level, below the dotted 1 um line)" if peak_um < 1.0 else ""))
    for a in axes:
        a.grid(alpha=0.3)
    save(fig, out_png)


def _window_max(t: np.ndarray, y: np.ndarray, window_s: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Start time and largest value of each ``window_s`` window of a sampled series."""
    idx = np.floor((t - t[0]) / window_s).astype(int)
    starts = np.flatnonzero(np.r_[True, np.diff(idx) > 0])
    return t[starts], np.maximum.reduceat(y, starts)


def _joint_panels(n: int):
    """A figure with one panel per joint, two columns: (fig, axes (rows, 2))."""
    rows = (n + 1) // 2
    return plt.subplots(rows, 2, figsize=(12, 2.7 * rows), sharex=True, squeeze=False)


def _finish_joint_panels(fig, axes, n: int, ncol: int, xlabel: str, title: str, out_png: str | Path) -> None:
    """The unused panels off, one legend (the first panel's) under the figure, the x label, the title; saved."""
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    handles, labels = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=ncol, fontsize=8, bbox_to_anchor=(0.5, 0.0))
    for ax in axes[-1]:
        ax.set_xlabel(xlabel)
    fig.suptitle(title)
    save(fig, out_png, rect=(0, 0.04, 1, 1))


def follow_torques(ts: pd.DataFrame, limits: dict, case: str, out_png: str | Path) -> None:
    """Per joint: the torque the command would need (before limiting) and the follower's (after),
    both limits in the scale of every panel, the periods with the limit active shaded, the
    segment ends (rest at a waypoint) as vertical lines."""
    cols = list(limits)
    n = len(cols)
    fig, axes = _joint_panels(n)
    t = ts.t_s.to_numpy()
    ends = t[np.flatnonzero(np.diff(ts.segment.to_numpy()))]
    for ax, col in zip(axes.ravel(), cols):
        lim = limits[col]
        before = ts[col.replace("tau_", "tau_cmd_")]
        if ts.limited.any():
            ax.fill_between(t, -1.2 * lim, 1.2 * lim, where=ts.limited.to_numpy(), color="tab:red", alpha=0.1,
                            step="mid", lw=0, label="a torque limit active")
        for e in ends:
            ax.axvline(e, color="0.6", lw=0.8, ls="-")
        ax.plot(t, before, "--", color="tab:blue", lw=1, label="command (before limiting)")
        ax.plot(t, ts[col], color="black", lw=1, label="followed (after)")
        ax.axhline(lim, color="tab:red", ls=":", lw=1.2, label="±limit")
        ax.axhline(-lim, color="tab:red", ls=":", lw=1.2)
        peak = ts[col].abs().max() / lim
        top = 1.2 * max(lim, before.abs().max(), ts[col].abs().max())
        ax.set_ylim(-top, top)
        if max(before.abs().max(), ts[col].abs().max()) < 1e-6 * lim:
            ax.text(0.5, 0.75, "no load on this path (|τ| < 1e-6 of the limit)", transform=ax.transAxes,
                    ha="center", va="center", fontsize=9, color="0.3")
        ax.set(ylabel="torque [N m]", title=f"joint {col.split('_')[1][1:]}: limit ±{lim:g} N m, "
                                            f"followed peak {100 * peak:.1f}%")
        ax.grid(alpha=0.3)
    _finish_joint_panels(fig, axes, n, 4, "time t [s]", f"{case}: joint torques before and after limiting"
                         + (" (grey lines: segment ends, where the arm rests at a waypoint)" if len(ends) else ""), out_png)


def follow_torque_split(ts: pd.DataFrame, limits: dict, case: str, terms: str, out_png: str | Path) -> None:
    """Per joint, along the path: the follower's motor torque and its parts, the link dynamics (links and
    payload: M q'' + C q' + g), the drives' reflected rotor inertia (armature q'') and their friction,
    with the ±limit; ``terms`` names the model's terms (e.g. 'links+armature+coulomb+viscous')."""
    cols = list(limits)
    n = len(cols)
    fig, axes = _joint_panels(n)
    s = ts.s_m.to_numpy()
    for ax, col in zip(axes.ravel(), cols):
        lim = limits[col]
        total = ts[col].to_numpy()
        arm, fric = ts[col.replace("tau_", "tau_armature_")].to_numpy(), ts[col.replace("tau_", "tau_friction_")].to_numpy()
        links = total - arm - fric
        ax.plot(s, links, color="tab:blue", lw=1, label="link dynamics (links, payload)")
        ax.plot(s, arm, color="tab:orange", lw=1, label="rotor inertia (armature q̈)")
        ax.plot(s, fric, color="tab:green", lw=1, label="friction (Coulomb + viscous)")
        ax.plot(s, total, color="black", lw=1.4, label="motor torque (their sum)")
        ax.axhline(lim, color="tab:red", ls=":", lw=1.2, label="±limit")
        ax.axhline(-lim, color="tab:red", ls=":", lw=1.2)
        top = 1.15 * max(lim, np.abs(total).max(), np.abs(links).max())
        ax.set_ylim(-top, top)
        ax.set(ylabel="torque [N m]", title=f"joint {col.split('_')[1][1:]}: peak {np.abs(total).max():.3g} of ±{lim:g} "
                                            f"N m (rotor ≤{np.abs(arm).max():.2g}, friction ≤{np.abs(fric).max():.2g})")
        ax.grid(alpha=0.3)
    _finish_joint_panels(fig, axes, n, 5, "path coordinate s [m]",
                         f"{case}: the follower's joint torques split by term along the path (model: "
                         f"{terms.replace('+', ' + ')})" + ("" if terms != "links" else "; the robot file states no drives"),
                         out_png)


def follow_infeasible(reason: str, shortfall: dict | None, limits: dict, case: str, out_png: str | Path) -> None:
    """A path the arm cannot follow: why (``reason``) and, when a torque cannot be met (``shortfall``:
    the output, the torque needed and its limit, N m), each joint's limit against what the path needs,
    in % of the limit on a log axis (a need many times the limit stays readable)."""
    fig, ax = plt.subplots(figsize=(10, 4.8))
    names = list(limits)
    need = np.zeros(len(names))
    if shortfall:
        need[names.index(shortfall["output"])] = 100 * shortfall["needed_nm"] / shortfall["limit_nm"]
    y = np.arange(len(names))
    ax.barh(y, np.full(len(names), 100.0), color="0.85", label="limit (100 %)")
    if shortfall:
        k = names.index(shortfall["output"])
        ax.barh([k], [need[k]], color="tab:red", height=0.5,
                label=f"needed {shortfall['what']}: {shortfall['needed_nm']:.3g} N m")
        ax.set_xscale("log")
        ax.set_xlim(1.0, max(1e3, 3 * need[k]))
        ax.legend(fontsize=8, loc="upper right")
    ax.axvline(100.0, color="tab:red", ls=":", lw=1.2)
    ax.set_yticks(y, [f"joint {n.split('_')[1][1:]} (±{limits[n]:g} N m)" for n in names])
    ax.set(xlabel="torque [% of the joint's limit]",
           title=f"{case}: the path cannot be followed under these torque limits")
    wrapped = textwrap.fill(reason, 120)
    fig.text(0.01, 0.01, wrapped, fontsize=8, va="bottom", ha="left", color="0.2")
    save(fig, out_png, rect=(0, 0.12, 1, 1))
