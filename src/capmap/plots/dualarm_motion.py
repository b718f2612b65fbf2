"""Figures of the dual-arm motion against the robot's limits: joint positions, joint velocities (on a broken axis:
the data at their scale, the limits beyond the break) and joint torques holding the panel. Each figure's title is its
verdict, in one line; what the curves are, in its caption (workflow/report)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import legend_beside, on_top, plt, save
from capmap.plots.dualarm import phases, pre_insertion

__all__ = ["joints", "velocities", "torques"]

BREAK = 50.0  # % of the limit: velocities all below it are drawn on a broken axis


def _percent(traj: pd.DataFrame, meta: dict, q: bool):
    """The joints' names, their positions (``q``) or velocities, those in % of the range or of the limit, the margins
    to the nearer limit (rad or rad/s) and the node and joint that come closest to a limit."""
    names = meta["joints"]
    lo = np.asarray(meta["q_lower"]) if q else -np.asarray(meta["v_max"])
    hi = np.asarray(meta["q_upper"]) if q else np.asarray(meta["v_max"])
    vals = np.column_stack([traj[f"q_{n}_rad" if q else f"qd_{n}_rad_s"].to_numpy() for n in names])
    pct = 100 * (vals - lo) / (hi - lo) if q else 100 * vals / hi
    margin = np.minimum(vals - lo, hi - vals)
    k, c = np.unravel_index(int(np.argmin(margin if q else margin / hi)), margin.shape)
    return names, lo, hi, vals, pct, margin, (k, c)


def _curves(ax, t, pct, names, mine, closest, peaks: bool) -> None:
    """One arm's joints (``mine``), the one ``closest`` (node k, joint c) to a limit thicker and circled, named."""
    k, c = closest
    for i, j in enumerate(mine):
        ax.plot(t, pct[:, j], lw=2.2 if j == c else 1.3, color=f"C{i}", zorder=3 if j == c else on_top(pct[:, mine], i),
                label=names[j] + (f": peak {np.abs(pct[:, j]).max():.1f} %" if peaks else ""))
    if c in mine:
        ax.plot(t[k], pct[k, c], "o", ms=11, mfc="none", mec="black", mew=2, zorder=4, label="closest to a limit")
        ax.annotate(names[c], (t[k], pct[k, c]), xytext=(8, -14 if pct[k, c] < 0 else 8), textcoords="offset points",
                    fontsize=8.5, fontweight="bold")


def joints(traj: pd.DataFrame, meta: dict, out_png: str | Path) -> None:
    """Each joint's position as % of its range, one panel per arm with the limits drawn (0 / 100 % of the range); the
    joint that comes closest to a limit (in rad) marked on its curve and named in the title with its margin."""
    names, lo, hi, vals, pct, margin, (k, c) = _percent(traj, meta, q=True)
    t = traj.t_s.to_numpy()
    fig, axes = plt.subplots(2, 1, figsize=(12, 7.8), sharex=True, layout="constrained")
    for ax, side in zip(axes, ("left", "right")):
        _curves(ax, t, pct, names, [j for j, n in enumerate(names) if n.startswith(side)], (k, c), peaks=False)
        for y in (0, 100):
            ax.axhline(y, color="tab:red", ls="--", lw=1.2, label="joint limit" if y else None)
        ax.set(ylim=(-15, 115), ylabel=f"{side} arm: position\n[% of its range: 0 = lower, 100 = upper limit]")
        phases(ax, pre_insertion(traj), float(t[-1]))
        ax.grid(alpha=0.3)
        legend_beside(ax)
    axes[-1].set_xlabel("time t [s]")
    side = "lower" if vals[k, c] - lo[c] <= hi[c] - vals[k, c] else "upper"
    fig.suptitle(f"Joint positions of both arms: {'all within their limits' if (margin >= 0).all() else 'a LIMIT IS EXCEEDED'}"
                 f", closest {names[c]}, {margin[k, c]:.3f} rad from its {side} limit at t = {t[k]:.1f} s", fontsize=12)
    save(fig, out_png)


def _broken(panel, span: float) -> tuple:
    """Three axes stacked in the (sub)figure ``panel``: a thin strip about +100 %, the data's scale ±``span``, a thin
    strip about -100 %, the breaks between them marked (//); the limits drawn and named in the strips."""
    top, main, bottom = panel.subplots(3, 1, height_ratios=[0.14, 1, 0.14])
    cut = dict(marker=[(-1, -0.5), (1, 0.5)], ms=10, ls="none", color="black", mew=1, clip_on=False)
    for strip, y, edge in ((top, 100, 0), (bottom, -100, 1)):
        strip.axhline(y, color="tab:red", ls="--", lw=1.2)
        strip.set(ylim=(y - 8, y + 8), yticks=[y])
        strip.tick_params(bottom=edge == 1)
        strip.spines["bottom" if edge == 0 else "top"].set_visible(False)
        strip.plot([0, 1], [edge, edge], transform=strip.transAxes, **cut)
        strip.text(0.995, 0.5, f"joint limit {y:+d} %", transform=strip.transAxes, color="tab:red", fontsize=8.5,
                   ha="right", va="center", bbox=dict(facecolor="white", edgecolor="none", pad=1))
    main.spines[["top", "bottom"]].set_visible(False)
    main.plot([0, 1, 0, 1], [1, 1, 0, 0], transform=main.transAxes, **cut)
    main.set(ylim=(-span, span))
    main.tick_params(bottom=False)
    return top, main, bottom


def velocities(traj: pd.DataFrame, meta: dict, out_png: str | Path) -> None:
    """Each joint's velocity in % of its limit, one panel per arm; far below the limits (every one under ``BREAK`` %)
    on a broken axis: the data at their scale, the ±100 % limits in thin strips beyond the breaks (else one axis to
    the limits). The joint closest to a limit marked on its curve and named in the title with its peak."""
    names, lo, hi, vals, pct, margin, (k, c) = _percent(traj, meta, q=False)
    t, peak = traj.t_s.to_numpy(), float(np.abs(pct).max())
    fig = plt.figure(figsize=(12, 8.4), layout="constrained")
    fig.get_layout_engine().set(h_pad=0.03, hspace=0.0)
    span = 1.25 * max(peak, 1.0)
    axes, mains = [], []
    for panel, side in zip(fig.subfigures(2, 1, hspace=0.04), ("left", "right")):
        top, ax, bottom = _broken(panel, span) if peak < BREAK else (None, panel.subplots(), None)
        _curves(ax, t, pct, names, [j for j, n in enumerate(names) if n.startswith(side)], (k, c), peaks=True)
        if top is None:
            for y in (-100, 100):
                ax.axhline(y, color="tab:red", ls="--", lw=1.2, label="joint limit ±100 %" if y > 0 else None)
            ax.set(ylim=(-max(115, 1.1 * peak), max(115, 1.1 * peak)))
        ax.set_ylabel(f"{side} arm: velocity\n[% of its limit]")
        phases(ax, pre_insertion(traj), float(t[-1]))
        legend_beside(ax)
        axes += [a for a in (top, ax, bottom) if a is not None]
        mains += [ax]
    mains[1].sharey(mains[0])  # the same ticks: the two panels' axes aligned
    for a in axes[1:]:
        a.sharex(axes[0])
    for a in axes:
        a.grid(alpha=0.3)
        a.tick_params(labelbottom=a is axes[-1])
    axes[-1].set_xlabel("time t [s]")
    within = "all within their limits" if (margin >= 0).all() else "a LIMIT IS EXCEEDED"
    fig.suptitle(f"Joint velocities {within}: peak {abs(pct[k, c]):.1f} % of the limit ({names[c]} at "
                 f"{t[k]:.1f} s, {abs(vals[k, c]):.3f} of {hi[c]:g} rad/s)", fontsize=12)
    save(fig, out_png)


def torques(tq: pd.DataFrame, meta: dict, t_pre: float, out_png: str | Path) -> None:
    """Each joint's |torque| in % of its effort limit with the least-norm internal force between the grippers (the
    torques the verdict is on), per arm, the limit drawn; black dotted: the arm's peak with the best internal force
    (the least any internal force allows; said once when both arms' are alike). ``meta``: the torques' provenance
    (joints, effort_nm, panel_kg)."""
    names, effort, panel_kg = meta["joints"], np.asarray(meta["effort_nm"]), meta["panel_kg"]
    ratio = np.column_stack([100 * tq[f"tau_{n}_nm"].abs().to_numpy() / effort[c] for c, n in enumerate(names)])
    best = np.column_stack([100 * tq[f"tau_best_{n}_nm"].abs().to_numpy() / effort[c] for c, n in enumerate(names)])
    arms = {side: [c for c, n in enumerate(names) if n.startswith(side)] for side in ("left", "right")}
    best_arm = {side: best[:, mine].max(axis=1) for side, mine in arms.items()}
    alike = np.allclose(best_arm["left"], best_arm["right"], rtol=1e-3, atol=1e-6)
    fig, axes = plt.subplots(2, 1, figsize=(12, 7.6), sharex=True)
    for (side, mine), ax in zip(arms.items(), axes):
        for i, c in enumerate(mine):
            ax.plot(tq.t_s, ratio[:, c], lw=1.4, color=f"C{i}", zorder=on_top(ratio[:, mine], i),
                    label=f"{names[c]}: peak {ratio[:, c].max():.2g} %")
        said = alike and side == "right"
        ax.plot(tq.t_s, best_arm[side], color="black", ls=":", lw=1.6, label="best internal force (as above)" if said else
                f"best internal force: peak {best_arm[side].max():.0f} %" + ("\n(both arms alike)" if alike else ""))
        ax.axhline(100, color="tab:red", lw=1.2, ls="--", label="effort limit")
        ax.set(ylabel=f"{side} arm\n|torque| / effort limit [%]", ylim=(-4, 115))
        phases(ax, t_pre, float(tq.t_s.iloc[-1]))
        ax.grid(alpha=0.3)
        legend_beside(ax)
    axes[-1].set_xlabel("time t [s]")
    k, c = np.unravel_index(int(ratio.argmax()), ratio.shape)
    verdict = "EXCEED the effort limits" if ratio.max() > 100 else "within the effort limits"
    fig.suptitle(f"Joint torques holding the {panel_kg:g} kg panel {verdict}: peak {ratio.max():.0f} % ({names[c]} at "
                 f"{tq.t_s.iloc[k]:.1f} s)", fontsize=12)
    save(fig, out_png)
