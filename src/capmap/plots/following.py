"""Figures of torque-limited following: progress along the path and torques before/after limiting."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import plt, save

__all__ = ["follow_progress", "follow_torques"]


def follow_progress(ts: pd.DataFrame, tp: pd.DataFrame, case: str, out_png: str | Path) -> None:
    """Path coordinate and speed: command, torque-limited follower, TOPP-RA; lag; path deviation."""
    fig, axes = plt.subplots(4, 1, figsize=(11, 11), sharex=True)
    ax = axes[0]
    ax.plot(ts.t_s, ts.s_cmd_m, "--", color="tab:blue", lw=1.2, label="command s (S-curve)")
    ax.plot(ts.t_s, ts.s_m, color="black", lw=1.2, label="followed s")
    ax.plot(tp.t_s, tp.s_m, ":", color="tab:green", lw=1.2, label="TOPP-RA (time-optimal, no jerk limit)")
    ax.set(ylabel="s [m]", title=f"{case}: path coordinate")
    ax.legend(fontsize=8)
    ax = axes[1]
    ax.plot(ts.t_s, ts.sd_cmd_mps, "--", color="tab:blue", lw=1.2, label="command")
    ax.plot(ts.t_s, ts.sd_mps, color="black", lw=1.2, label="followed")
    ax.plot(tp.t_s, tp.sd_mps, ":", color="tab:green", lw=1.2, label="TOPP-RA")
    lim = ts.limited.to_numpy()
    if lim.any():
        ax.fill_between(ts.t_s, 0, ts.sd_mps.max() * 1.05, where=lim, color="tab:red", alpha=0.12, step="mid",
                        label="torque limit active")
    ax.set(ylabel="sd [m/s]")
    ax.legend(fontsize=8)
    axes[2].plot(ts.t_s, 1e3 * ts.lag_m, color="tab:purple")
    axes[2].set(ylabel="lag s_cmd - s [mm]")
    axes[3].plot(ts.t_s, 1e6 * ts.deviation_m, color="tab:brown", label="position")
    axes[3].set(ylabel="path deviation [um]", xlabel="t [s]",
                title=f"deviation of the joint command from the line: max {1e6 * ts.deviation_m.max():.2f} um, "
                      f"{np.rad2deg(ts.deviation_rad.max()) * 3600:.3f} arcsec")
    for a in axes:
        a.grid(alpha=0.3)
    save(fig, out_png)


def follow_torques(ts: pd.DataFrame, limits: dict, case: str, out_png: str | Path) -> None:
    """Per joint: the torque the command would need (before limiting) and the follower's (after)."""
    cols = list(limits)
    n = len(cols)
    fig, axes = plt.subplots((n + 1) // 2, 2, figsize=(12, 2.6 * ((n + 1) // 2)), sharex=True, squeeze=False)
    for ax, col in zip(axes.ravel(), cols):
        lim = limits[col]
        before = ts[col.replace("tau_", "tau_cmd_")]
        ax.plot(ts.t_s, before, "--", color="tab:blue", lw=1, label="command (before limiting)")
        ax.plot(ts.t_s, ts[col], color="black", lw=1, label="followed (after)")
        ax.axhline(lim, color="tab:red", ls=":", lw=1.2)
        ax.axhline(-lim, color="tab:red", ls=":", lw=1.2)
        peak = ts[col].abs().max() / lim
        top = 1.25 * max(lim if peak > 0.5 else 0, before.abs().max(), ts[col].abs().max(), 1e-9)
        ax.set_ylim(-top, top)
        ax.set(ylabel="[N m]", title=f"{col}: limit {lim:g} N m, followed peak {100 * peak:.2f}%")
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    axes.ravel()[0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{case}: joint torques before and after limiting (red dotted: +-limit)")
    save(fig, out_png)
