"""Figures of the capacity map: the map itself, the workspace with the verified paths, and
the loads over time against their limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import plt, save

__all__ = ["capacity_map", "workspace_paths", "load_series", "PATH_STYLE"]


def capacity_map(vox: pd.DataFrame, out_png: str | Path, title: str = "Dynamic load-carrying capacity") -> None:
    """3D scatter of reachable voxel centres coloured by capacity, and the fullest z-slice."""
    reach = vox[vox.n_reachable > 0]
    fig = plt.figure(figsize=(13, 5.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    if len(reach):
        vmin, vmax = np.nanpercentile(reach.capacity_kg, [1, 99])
        sc = ax.scatter(reach.x_m, reach.y_m, reach.z_m, c=reach.capacity_kg, s=6, cmap="viridis", vmin=vmin, vmax=vmax)
        fig.colorbar(sc, ax=ax, shrink=0.7, label="capacity [kg]")
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]", title=f"{title}\n{len(reach)} reachable voxels")
    ax2 = fig.add_subplot(1, 2, 2)
    if len(reach):
        k = reach.k.value_counts().idxmax()
        sl = vox[vox.k == k]
        nx, ny = sl.i.max() + 1, sl.j.max() + 1
        img = np.full((ny, nx), np.nan)
        img[sl.j.to_numpy(), sl.i.to_numpy()] = sl.capacity_kg.to_numpy()
        dx = vox.attrs["capmap"]["grid"]["edge_m"]
        x0, y0 = sl.x_m.min(), sl.y_m.min()
        im = ax2.imshow(img, origin="lower", cmap="viridis", vmin=vmin, vmax=vmax,
                        extent=[x0 - dx / 2, x0 + (nx - 0.5) * dx, y0 - dx / 2, y0 + (ny - 0.5) * dx])
        fig.colorbar(im, ax=ax2, label="capacity [kg]")
        ax2.set(xlabel="x [m]", ylabel="y [m]", title=f"slice z = {sl.z_m.iloc[0]:.3f} m (white: unreachable)")
    save(fig, out_png)


PATH_STYLE = {"direct": {"color": "tab:red", "ls": "--", "label": "direct line"},
              "planned": {"color": "black", "ls": "-", "label": "planned path"}}


def workspace_paths(vox: pd.DataFrame, ts: pd.DataFrame, payload_kg: float, out_png: str | Path) -> None:
    """Voxels near the paths coloured by capacity (grey: below the payload), the direct line and
    the planned path in 3D; and the x-y slice through the goal's voxel layer."""
    reach = vox[vox.n_reachable > 0]
    dx = vox.attrs["capmap"]["grid"]["edge_m"]
    lo = ts[["x_m", "y_m", "z_m"]].min().to_numpy() - 1.5 * dx
    hi = ts[["x_m", "y_m", "z_m"]].max().to_numpy() + 1.5 * dx
    xyz = reach[["x_m", "y_m", "z_m"]].to_numpy()
    near = reach[np.all((xyz >= lo) & (xyz <= hi), axis=1)]
    vmin, vmax = (np.nanpercentile(reach.capacity_kg, [1, 99]) if len(reach) else (0, 1))
    fig = plt.figure(figsize=(13, 5.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    strong = near[near.capacity_kg >= payload_kg]
    weak = near[near.capacity_kg < payload_kg]
    sc = ax.scatter(strong.x_m, strong.y_m, strong.z_m, c=strong.capacity_kg, s=8, cmap="viridis", vmin=vmin,
                    vmax=vmax, alpha=0.25, depthshade=False)
    ax.scatter(weak.x_m, weak.y_m, weak.z_m, c="0.5", s=10, marker="x", alpha=0.5, label=f"< {payload_kg:g} kg")
    for name, g in ts.groupby("path", observed=True):
        ax.plot(g.x_m, g.y_m, g.z_m, lw=2.5, zorder=10, **PATH_STYLE.get(name, {}))
    first = ts.iloc[0]
    last = ts[ts.path == ts.path.iloc[0]].iloc[-1]
    ax.scatter([first.x_m], [first.y_m], [first.z_m], c="tab:green", s=60, marker="o", label="start")
    ax.scatter([last.x_m], [last.y_m], [last.z_m], c="tab:orange", s=80, marker="*", label="goal")
    fig.colorbar(sc, ax=ax, shrink=0.7, label="voxel capacity [kg]")
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]", title=f"Voxels near the paths, payload {payload_kg:g} kg",
           xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]))
    ax.set_box_aspect(hi - lo)
    ax.legend(loc="upper left", fontsize=8)
    ax2 = fig.add_subplot(1, 2, 2)
    k_goal = int(np.floor((last.z_m - vox.attrs["capmap"]["grid"]["lower_m"][2]) / dx))
    sl = vox[vox.k == k_goal]
    nx, ny = int(sl.i.max()) + 1, int(sl.j.max()) + 1
    img = np.full((ny, nx), np.nan)
    img[sl.j.to_numpy(), sl.i.to_numpy()] = sl.capacity_kg.to_numpy()
    x0, y0 = sl.x_m.min(), sl.y_m.min()
    extent = [x0 - dx / 2, x0 + (nx - 0.5) * dx, y0 - dx / 2, y0 + (ny - 0.5) * dx]
    im = ax2.imshow(img, origin="lower", cmap="viridis", vmin=vmin, vmax=vmax, extent=extent)
    ax2.contour(np.where(np.isnan(img), -1, img), levels=[payload_kg], colors="white", linewidths=1.2,
                extent=extent, origin="lower")
    for name, g in ts.groupby("path", observed=True):
        ax2.plot(g.x_m, g.y_m, lw=1.5, **PATH_STYLE.get(name, {}))
    ax2.plot(last.x_m, last.y_m, "*", color="tab:orange", ms=12)
    fig.colorbar(im, ax=ax2, label="voxel capacity [kg]")
    ax2.set(xlabel="x [m]", ylabel="y [m]",
            title=f"goal layer z = {sl.z_m.iloc[0]:.3f} m; white: {payload_kg:g} kg contour")
    ax2.legend(fontsize=8)
    save(fig, out_png)


def load_series(ts: pd.DataFrame, columns: list[str], limits: dict, title: str, out_png: str | Path) -> None:
    """One panel per path: the given outputs over time with their +-limit lines."""
    paths = list(ts.path.cat.categories if hasattr(ts.path, "cat") else ts.path.unique())
    fig, axes = plt.subplots(len(paths), 1, figsize=(11, 3.6 * len(paths)), squeeze=False, sharex=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, name in zip(axes[:, 0], paths):
        g = ts[ts.path == name]
        for n, col in enumerate(columns):
            c = colors[n % len(colors)]
            ax.plot(g.t_s, g[col], color=c, lw=1.2, label=col)
            same = len({limits[k] for k in columns}) == 1  # one pair of grey lines serves all
            if not same or n == 0:
                lim = limits[col]
                ax.axhline(lim, color="0.3" if same else c, ls=":", lw=1.2)
                ax.axhline(-lim, color="0.3" if same else c, ls=":", lw=1.2)
        peak = max(np.nanmax(np.abs(g[c]) / limits[c]) for c in columns)
        top = 1.4 * max(max(limits[c] for c in columns), max(np.nanmax(np.abs(g[c])) for c in columns))
        ax.set_ylim(-top, top)  # room for the legend above the limit lines
        ax.set(ylabel=columns[0].rsplit("_", 1)[-1].replace("nm", "[N m]").replace("n", "[N]"),
               title=f"{PATH_STYLE.get(name, {}).get('label', name)}: peak {100 * peak:.0f}% of limit (dotted: +-limit)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=len(columns), loc="upper right")
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(title + ("" if "planned" in paths else " (no planned path at this payload: see the summary)"))
    save(fig, out_png)
