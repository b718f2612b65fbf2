"""Figures of the dual-arm assembly's solution: task-constraint errors, safety distances and the solver's convergence
(the joints, velocities and torques: :mod:`capmap.plots.dualarm_motion`; the animation: :mod:`capmap.plots.dualarm_scene`).
Each figure's title is its verdict, in one line; what the curves are, in its caption (workflow/report)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.ticker import FuncFormatter

from capmap.plots.common import legend_beside, plt, save

__all__ = ["constraint_errors", "distances", "convergence", "phases", "pre_insertion"]

SPEC_M = 7e-7  # docs/spec/dual-arm-assembly.md: "the paper's reported result: maximum closed-chain / path error below 7e-7 m"
ZERO = 1e-16  # where an exact zero is drawn on a log scale (its tick reads 0)
NEAR_M = 1e-6  # a pair touches the margin where the distance comes within 1 µm of it
MARKERS = "osD^v<>"


def phases(ax, t_pre: float | None, t_end: float) -> None:
    """The pre-insertion pose (dashed grey, in the legend) and the phases' names in the top 3 % of the axes
    (the figures leave that band free of data)."""
    if t_pre is None:
        return
    ax.axvline(t_pre, color="0.45", lw=0.9, ls="--", label=f"pre-insertion pose ({t_pre:.1f} s)")
    top = ax.get_xaxis_transform()
    ax.text(t_pre / 2, 0.985, "transfer", transform=top, ha="center", va="top", fontsize=8, color="0.35")
    ax.text((t_pre + t_end) / 2, 0.985, "insertion", transform=top, ha="center", va="top", fontsize=8, color="0.35")


def pre_insertion(traj: pd.DataFrame) -> float | None:
    """The time of the pre-insertion node (None: none)."""
    t = traj.t_s[traj.phase == "pre_insertion"]
    return float(t.iloc[0]) if len(t) else None


def _held(worst_m: float, worst_rad: float, tolerance: float) -> str:
    """The constraint errors' verdict: within the solver's tolerance (what decides), else at least the spec's 7e-7 m."""
    worst = f"largest error {worst_m:.1e} m, {worst_rad:.1e} rad"
    if max(worst_m, worst_rad) <= tolerance:
        margin = f"{SPEC_M / worst_m:.0f}× under" if worst_m > 0 else "under"
        return f"held at every node: {worst} ≤ tolerance {tolerance:g} ({margin} the spec's 7e-7 m)"
    if worst_m <= SPEC_M:
        return f"ABOVE the solver's tolerance {tolerance:g}: {worst}, within the spec's 7e-7 m"
    return f"NOT HELD: {worst}, above the solver's tolerance {tolerance:g} and the spec's 7e-7 m"


def constraint_errors(traj: pd.DataFrame, out_png: str | Path, tolerance: float) -> None:
    """Closed-chain and path errors at the nodes (each the norm of its 3-vector; log scale, an exact zero drawn at
    1e-16, its tick reading 0) against the solver's ``tolerance`` (m and rad: what decides), the position also
    against the spec's 7e-7 m; the verdict in the title."""
    fig, axes = plt.subplots(2, 1, figsize=(12, 6.6), sharex=True)
    rows = ((axes[0], "position", "m", ("closed_chain_pos_err_m", "path_err_m")),
            (axes[1], "rotation", "rad", ("closed_chain_rot_err_rad", "path_err_rad")))
    zero = FuncFormatter(lambda v, _: "0" if np.isclose(v, ZERO, rtol=1e-3, atol=0) else f"$10^{{{round(np.log10(v))}}}$")
    worst = []
    for ax, what, unit, cols in rows:
        for col, label in zip(cols, ("closed chain", "panel's path")):
            ax.semilogy(traj.t_s, np.maximum(traj[col], ZERO), lw=1.4, label=label)
        worst.append(max(float(traj[c].max()) for c in cols))
        ax.axhline(tolerance, color="tab:red", ls="--", lw=1.3, label=f"solver's tolerance {tolerance:g} {unit}")
        if unit == "m":
            ax.axhline(SPEC_M, color="0.35", ls="-.", lw=1.1, label="spec's reference 7e-7 m")
        ax.set(ylabel=f"{what} error [{unit}]",
               ylim=(ZERO / 5, 300 * max(tolerance, worst[-1], SPEC_M if unit == "m" else 0.0)))
        ax.yaxis.set_major_formatter(zero)
        phases(ax, pre_insertion(traj), float(traj.t_s.iloc[-1]))
        ax.grid(alpha=0.3, which="major")
        legend_beside(ax)
    axes[-1].set_xlabel("time t [s]")
    fig.suptitle(f"Task constraints {_held(worst[0], worst[1], tolerance)}", fontsize=12)
    save(fig, out_png)


def _touches(fine: pd.DataFrame, traj: pd.DataFrame, margin_m: float, active: list) -> list[tuple[str, float, float]]:
    """Where a pair touches the margin: each stretch of the finer grid within ``NEAR_M`` of it, at its lowest (pair,
    t s, distance m); and each pair of ``active`` (name, distance m, time s, ...) that never does, at its closest."""
    d, t = fine.min_distance_m.to_numpy(), fine.t_s.to_numpy()
    pair = (fine.min_distance_pair.to_numpy() if "min_distance_pair" in fine else
            traj.min_distance_pair.to_numpy()[np.clip(np.searchsorted(traj.t_s.to_numpy(), t), 0, len(traj) - 1)])
    edges = np.flatnonzero(np.diff(np.r_[0, (d <= margin_m + NEAR_M).astype(int), 0]))
    out = []
    for a, b in zip(edges[::2], edges[1::2]):
        k = a + int(np.argmin(d[a:b]))
        out.append((str(pair[k]), float(t[k]), float(d[k])))
    return out + [(name, float(tm), float(dm)) for name, dm, tm, *_ in active if name not in {p for p, _, _ in out}]


def _mark(ax, zoom, touches: list, margin_m: float) -> None:
    """The ``touches`` on both panels, one marker per pair (named with its times in the top panel's legend)."""
    pairs = list(dict.fromkeys(p for p, _, _ in touches))
    if pairs:
        ax.plot([], [], " ", label="where a pair touches the margin:")
    for i, name in enumerate(pairs):
        mine = [(tm, dm) for p, tm, dm in touches if p == name]
        tm, dm = np.array(mine).T
        style = dict(marker=MARKERS[i % len(MARKERS)], ls="none", ms=10, mfc="none", mew=2, color=f"C{(i + 2) % 10}",
                     zorder=3)
        away = "" if dm.min() <= margin_m + NEAR_M else f" ({1e3 * dm.min():.2f} mm)"
        ax.plot(tm, 1e3 * dm, **style, label=f"{name}:\n{', '.join(f'{x:.2f}' for x in tm)} s{away}")
        zoom.plot(tm, 1e6 * (dm - margin_m), **style)


def distances(traj: pd.DataFrame, fine: pd.DataFrame, margin_m: float, active: list, tolerance: float,
              out_png: str | Path) -> None:
    """The smallest safety distance over all pairs of collision volumes on the finer grid (the executed motion), the
    margin and contact drawn, every touch of the margin marked and named (``active``: the pairs within 1 cm, name,
    distance, time, ...: those that never touch it marked at their closest); below, zoomed to µm about the margin:
    the nodes (held to the solver's ``tolerance``, m) and the finer grid between them. The verdict in the title."""
    fig, (ax, zoom) = plt.subplots(2, 1, figsize=(12, 7.2), sharex=True, height_ratios=[2, 1.1])
    d_fine, margin = 1e3 * fine.min_distance_m, 1e3 * margin_m
    ax.plot(fine.t_s, d_fine, color="tab:blue", lw=1.6, label="executed motion")
    ax.axhline(margin, color="tab:orange", ls="--", label=f"safety margin {margin:g} mm")
    ax.axhline(0.0, color="tab:red", lw=1.2, label="contact")
    top = min(float(d_fine.max()), 200.0)
    ax.set(ylabel="smallest distance [mm]", ylim=(min(-1.0, d_fine.min() - 1), 1.15 * top + 3))
    phases(ax, pre_insertion(traj), float(fine.t_s.iloc[-1]))
    under_f, under_n = 1e6 * (fine.min_distance_m - margin_m), 1e6 * (traj.min_distance_m - margin_m)
    zoom.plot(fine.t_s, under_f, color="tab:blue", lw=1.2, label="between the nodes")
    zoom.plot(traj.t_s, under_n, ".", color="black", ms=3, label="at the nodes")
    zoom.axhline(0.0, color="tab:orange", ls="--", label="margin")
    _mark(ax, zoom, _touches(fine, traj, margin_m, active), margin_m)
    low = min(-1.0, 1.5 * float(under_f.min()))
    zoom.set(xlabel="time t [s]", ylabel="distance − margin [µm]", ylim=(low, 4 * abs(low)))
    for a in (ax, zoom):
        a.grid(alpha=0.3)
        legend_beside(a)
    low_f, node_low, tol = float(d_fine.min()), float(traj.min_distance_m.min()), 1e3 * tolerance
    zoom.set_title(f"zoom: between the nodes down to {1e3 * (margin - low_f):.2f} µm under the margin"
                   if low_f < margin - tol else "zoom: never under the margin between the nodes", fontsize=10, loc="left")
    free = min(low_f, 1e3 * node_low) > 0
    held = 1e3 * node_low >= margin - tol
    fig.suptitle(f"{'Collision-free' if free else 'IN COLLISION'}: smallest distance {min(low_f, 1e3 * node_low):.3f} mm,"
                 f" the {margin:g} mm margin {'held' if held else 'NOT held'} at the nodes", fontsize=12)
    save(fig, out_png)


def _result_ticks(ax, last: int) -> None:
    """Integer ticks for the iterations 0 .. ``last`` and one named "result" at last + 1."""
    step = max(1, int(np.ceil((last + 1) / 8)))
    ticks = list(range(0, last + 1, step))
    ax.set_xticks(ticks + [last + 1], [str(k) for k in ticks] + ["result"])


def convergence(outer: pd.DataFrame, out_png: str | Path, tolerance: float | None = None,
                node_errors: tuple[float, float] | None = None) -> None:
    """Per outer iteration of the augmented-Lagrangian loop: the constraint violations (the largest residual
    component at any node, each in its SI unit: m, rad or rad/s) against the loop's ``tolerance`` (it stops below
    it), with the result's largest node errors (``node_errors``: m, rad, the norms of constraint_errors.png) at a
    tick of their own, and, below, the penalty μ (dimensionless weight); the verdict in the title."""
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(11, 6.4), sharex=True, height_ratios=[2, 1])
    ax.semilogy(outer.outer, outer.eq_violation, "o-", label="equalities: chain, path, poses")
    ax.semilogy(outer.outer, np.maximum(outer.in_violation, ZERO), "s-", label="inequalities: distances, limits")
    last = max(float(outer.eq_violation.iloc[-1]), float(outer.in_violation.iloc[-1]))
    if tolerance is not None:
        ax.axhline(tolerance, color="tab:red", ls="--", lw=1.2, label=f"tolerance {tolerance:g}")
    end = int(outer.outer.iloc[-1])
    if node_errors is not None:
        ax.axvline(end + 0.5, color="0.6", lw=0.8)
        ax.plot([end + 1] * 2, node_errors, "D", ms=8, mfc="none", mew=1.6, color="tab:green", zorder=3,
                label=f"result at the nodes:\n{node_errors[0]:.1e} m, {node_errors[1]:.1e} rad")
    ax.set(ylabel="largest violation\n[m, rad or rad/s]")
    ax.grid(alpha=0.3)
    legend_beside(ax)
    ax2.semilogy(outer.outer, outer.mu, "^--", color="0.3")
    ax2.set(xlabel="outer iteration", ylabel="penalty μ")
    _result_ticks(ax2, end) if node_errors is not None else ax2.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
    ax2.grid(alpha=0.3)
    done = "converged" if tolerance is None or last <= tolerance else "did NOT converge"
    bound = "" if tolerance is None else f" {'≤' if last <= tolerance else '>'} tolerance {tolerance:g}"
    fig.suptitle(f"Solver {done} in {len(outer)} outer iterations ({int(outer.inner_iterations.sum())} inner): final "
                 f"violation {last:.1e}{bound}", fontsize=12)
    save(fig, out_png)
