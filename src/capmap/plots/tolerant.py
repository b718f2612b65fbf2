"""Figure of the failure-tolerant map beside the healthy arm's, and the volume each failure leaves."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import grid_corner, legend_beside, plt, save, voxel_layer

__all__ = ["TolerantContext", "tolerant_figure"]


def _curves(a, tol: pd.DataFrame, scopes: list, edge: float, payloads, top: float) -> None:
    """The volume carrying each payload M per scope (healthy, each joint failing at any swept angle, any joint):
    solid on the sweep, dashed on the sweep at twice the step (the step's convergence)."""
    m = np.linspace(0.0, top * 1.02, 400)

    def volume(values):
        v = np.sort(values[np.isfinite(values)])
        return (len(v) - np.searchsorted(v, m, side="left")) * edge**3

    for n, (scope, col, coarse) in enumerate(scopes):
        colour = "black" if scope == "healthy" else "tab:red" if scope == "any joint" else f"C{(n - 1) % 10}"
        lw = 2.4 if scope in ("healthy", "any joint") else 1.3
        reached = np.isfinite(tol[col]).sum() * edge**3
        label = ("healthy arm (best swept lock)" if scope == "healthy" else f"{scope} fails, any angle"
                 ) + ("" if reached else ": none reached")
        a.plot(m, volume(tol[col].to_numpy()), color=colour, lw=lw, label=label)
        if coarse:
            a.plot(m, volume(tol[coarse].to_numpy()), color=colour, lw=0.9, ls="--")
    a.plot([], [], color="0.4", lw=0.9, ls="--", label="same, every other swept angle")
    for p in payloads:
        a.axvline(p, color="0.3", ls=":", lw=1)
        a.text(p, 0.99, f" {p:g} kg", transform=a.get_xaxis_transform(), fontsize=8.5, va="top")
    a.set(xlabel="payload M [kg]", ylabel="volume of the voxels carrying M [m³]", xlim=(0, top * 1.02),
          title="the volume that carries each payload\n(a failure: at most this; finer steps can only lower it)")
    a.grid(alpha=0.3)
    legend_beside(a)


@dataclass(frozen=True)
class TolerantContext:
    """What the failure-tolerant figure tells of its run: the sweeps' ``grid`` (its provenance: lower_m, shape,
    edge_m), the task ``payloads_kg``, the lock reaching the fewest voxels ``worst_lock`` (joint, angle deg,
    voxels reached), the ``scopes`` to draw ((scope, its column, its column at twice the step or None), healthy
    first and any joint last), the task's start_m and goal_m (3,) m."""

    grid: dict
    payloads_kg: tuple[float, ...]
    worst_lock: tuple[int, float, int]
    scopes: list
    start_m: np.ndarray
    goal_m: np.ndarray


def tolerant_figure(tol: pd.DataFrame, c: TolerantContext, out_png: str | Path) -> None:
    """Three panels: the healthy arm's map (best swept lock) and the failure-tolerant map over the task
    start's voxel layer on one colour scale (when no voxel of the layer survives every joint's failure, the
    map of the joint whose failure leaves the most volume instead), and the volume carrying each payload."""
    grid, payloads, worst_lock, scopes, start_m, goal_m = c.grid, c.payloads_kg, c.worst_lock, c.scopes, c.start_m, c.goal_m
    edge = float(grid["edge_m"])
    fig, ax = plt.subplots(1, 3, figsize=(19, 6.5), layout="constrained")
    lo = grid_corner(tol, edge)
    k = int(np.clip(np.floor((start_m[2] - lo[2]) / edge), tol.k.min(), tol.k.max()))
    top = float(np.nanmax(tol.healthy_capacity_kg.to_numpy(), initial=1.0))
    z = lo[2] + (k + 0.5) * edge
    col, title = "tolerant_capacity_kg", "any single joint failing at any swept angle"
    if not np.isfinite(voxel_layer(tol, col, k, edge)[0]).any():
        per_joint = [(np.isfinite(tol[c]).sum(), s, c) for s, c, _ in scopes[1:-1]]
        _, scope, col = max(per_joint)
        title = f"{scope} failing at any swept angle\n(no voxel here survives every joint's failure)"
    for a, c, t in ((ax[0], "healthy_capacity_kg", "healthy arm (each voxel at its best swept lock)"), (ax[1], col, title)):
        img, extent = voxel_layer(tol, c, k, edge)
        a.set_facecolor("0.85")
        im = a.imshow(img, origin="lower", extent=extent, cmap="viridis", vmin=0, vmax=top, interpolation="nearest")
        a.plot(*start_m[:2], "o", ms=10, mfc="white", mec="black", label="task start")
        a.plot(*goal_m[:2], "*", ms=14, mfc="white", mec="black", label="task goal (its own layer)")
        a.set(xlabel="x [m]", ylabel="y [m]", aspect="equal", title=f"{t}\nvoxel layer z = {z:.2f} m")
    fig.colorbar(im, ax=ax[:2], shrink=0.85,
                 label="capacity [kg] (grey: no value; right: a failure leaves the voxel wholly or in part)")
    ax[0].legend(fontsize=8, loc="lower left")
    _curves(ax[2], tol, scopes, edge, payloads, top)
    n = int(tol.reachable_every_failure.sum())
    j, angle, reached = worst_lock
    fig.suptitle(f"What survives any one failure ({edge:g} m voxels): {n:,} voxels ({n * edge**3:,.1f} m³) stay reachable "
                 f"whichever joint fails at whichever swept angle; the lock reaching the fewest: joint {j} at {angle:g} deg "
                 f"({reached:,} of {len(tol):,} voxels)\nvalues are the least over the swept angles: between them a "
                 "failure can leave less (dashed: every other angle)", fontsize=11.5)
    save(fig, out_png)
