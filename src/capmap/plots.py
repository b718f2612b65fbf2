"""Figures (matplotlib, Agg backend). Plotting lives here, never in the numerics."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


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
    fig.tight_layout()
    Path(out_png).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110)
    plt.close(fig)
