"""Figure of the failure-tolerant map beside the healthy arm's, and the volume each failure leaves."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import grid_corner, legend_beside, plt, save, voxel_layer

__all__ = ["tolerant_figure"]


def _curves(a, tol: pd.DataFrame, edge: float, payloads, top: float) -> None:
    """The volume carrying each payload M: healthy, each joint failing at any swept angle, any joint."""
    m = np.linspace(0.0, top * 1.02, 400)
    joints = [c for c in tol.columns if c.startswith("tolerant_j")]
    curves = [("healthy_capacity_kg", "healthy arm (best swept lock)", dict(color="black", lw=2.2))]
    curves += [(c, f"joint {c[len('tolerant_j'):-len('_capacity_kg')]} fails, any angle",
                dict(color=f"C{n % 10}", lw=1.3)) for n, c in enumerate(joints)]
    curves += [("tolerant_capacity_kg", "any joint fails, any angle", dict(color="tab:red", lw=2.6, ls="--"))]
    for col, label, style in curves:
        v = np.sort(tol[col].dropna().to_numpy())
        a.plot(m, (len(v) - np.searchsorted(v, m, side="left")) * edge**3, label=label, **style)
    for p in payloads:
        a.axvline(p, color="0.3", ls=":", lw=1)
        a.text(p, 0.99, f" {p:g} kg", transform=a.get_xaxis_transform(), fontsize=8.5, va="top")
    a.set(xlabel="payload M [kg]", ylabel="volume of the voxels carrying M [m³]", xlim=(0, top * 1.02),
          title="the volume that carries each payload")
    a.grid(alpha=0.3)
    legend_beside(a)


def tolerant_figure(tol: pd.DataFrame, grid: dict, payloads, worst_lock: tuple[int, float, int],
                    start_m: np.ndarray, goal_m: np.ndarray, out_png: str | Path) -> None:
    """Three panels: the healthy arm's map (best swept lock) and the failure-tolerant map over the task
    start's voxel layer on one colour scale, and the volume carrying each payload (healthy, each joint,
    any joint). ``worst_lock``: the (joint, angle deg, voxels reached) of the lock reaching the fewest."""
    edge = float(grid["edge_m"])
    fig, ax = plt.subplots(1, 3, figsize=(19, 6.5), layout="constrained")
    lo = grid_corner(tol, edge)
    k = int(np.clip(np.floor((start_m[2] - lo[2]) / edge), tol.k.min(), tol.k.max()))
    top = float(np.nanmax(tol.healthy_capacity_kg.to_numpy(), initial=1.0))
    z = lo[2] + (k + 0.5) * edge
    for a, col, title in ((ax[0], "healthy_capacity_kg", "healthy arm (each voxel at its best swept lock)"),
                          (ax[1], "tolerant_capacity_kg", "any single joint failing at any swept angle")):
        img, extent = voxel_layer(tol, col, k, edge)
        a.set_facecolor("0.85")
        im = a.imshow(img, origin="lower", extent=extent, cmap="viridis", vmin=0, vmax=top, interpolation="nearest")
        a.plot(*start_m[:2], "o", ms=10, mfc="white", mec="black", label="task start")
        a.plot(*goal_m[:2], "*", ms=14, mfc="white", mec="black", label="task goal (its own layer)")
        a.set(xlabel="x [m]", ylabel="y [m]", aspect="equal", title=f"{title}\nvoxel layer z = {z:.2f} m")
    if not np.isfinite(voxel_layer(tol, "tolerant_capacity_kg", k, edge)[0]).any():
        ax[1].text(0.5, 0.5, "no voxel of this layer stays reachable\nwhatever joint fails at whatever angle",
                   transform=ax[1].transAxes, ha="center", va="center", fontsize=11,
                   bbox=dict(fc="white", ec="0.5"))
    fig.colorbar(im, ax=ax[:2], label="capacity [kg] (grey: not reached)", shrink=0.85)
    ax[0].legend(fontsize=8, loc="lower left")
    _curves(ax[2], tol, edge, payloads, top)
    n = int(tol.reachable_every_failure.sum())
    j, angle, reached = worst_lock
    fig.suptitle(f"What survives any one failure ({edge:g} m voxels): {n * edge**3:,.0f} m³ stay reachable whichever joint "
                 f"fails at whichever swept angle; the failure that decides most: joint {j} locked at {angle:g} deg "
                 f"reaches {reached} of {len(tol)} voxels", fontsize=11.5)
    save(fig, out_png)
