"""Shared figure helpers (matplotlib, Agg backend). Plotting lives in :mod:`capmap.plots`,
never in the numerics; each function takes DataFrames and writes one PNG."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

__all__ = ["plt", "save", "not_done_figure", "legend_beside", "on_top", "grid_corner", "voxel_layer"]


def save(fig, out_png: str | Path, rect: tuple[float, float, float, float] | None = None) -> None:
    """Lay out (within ``rect`` of the figure when given: room for a figure legend), write (110 dpi,
    parents created) and close a figure."""
    if not fig.get_layout_engine():
        fig.tight_layout(rect=rect)
    Path(out_png).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110)
    plt.close(fig)


def not_done_figure(title: str, reason: str, out_png: str | Path) -> None:
    """A figure for a result that is "cannot be done": its title and why, in words (no axes to read)."""
    import textwrap

    fig, ax = plt.subplots(figsize=(10, 3.6))
    ax.set_axis_off()
    ax.set_title(title, fontsize=13)
    ax.text(0.5, 0.5, textwrap.fill(reason, 100), ha="center", va="center", fontsize=9.5, wrap=True,
            transform=ax.transAxes, bbox={"boxstyle": "round", "facecolor": "#fdecea", "edgecolor": "tab:red"})
    save(fig, out_png)


def legend_beside(ax, **kw):
    """The axes' legend to their right, outside them (never on a curve or a limit line); ``kw`` to ``ax.legend``."""
    return ax.legend(**{"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0, "fontsize": 8,
                        "frameon": False, **kw})


def on_top(values, i: int) -> float:
    """Column i's curve's zorder (2 to 2.5) among the columns of ``values`` (n, k): the smaller its peak |value|, the
    higher, so that no small curve hides under a larger one."""
    rank = np.argsort(np.argsort(-np.abs(values).max(axis=0)))
    return 2 + rank[i] / (2 * len(rank))


def grid_corner(df: pd.DataFrame, edge: float) -> np.ndarray:
    """(3,) m: the corner of voxel (0, 0, 0) of the table's grid (centre = lower + (index + 1/2) edge)."""
    r = df.iloc[0]
    return np.array([r.x_m, r.y_m, r.z_m]) - (np.array([r.i, r.j, r.k], dtype=float) + 0.5) * edge


def voxel_layer(df: pd.DataFrame, column: str, k: int, edge: float) -> tuple[np.ndarray, list[float]]:
    """Image (ny, nx) of ``column`` over the voxel layer k (NaN: no value) and its imshow extent [m]."""
    i0, j0 = int(df.i.min()), int(df.j.min())
    nx, ny = int(df.i.max()) - i0 + 1, int(df.j.max()) - j0 + 1
    img = np.full((ny, nx), np.nan)
    sl = df[df.k == k]
    img[sl.j.to_numpy() - j0, sl.i.to_numpy() - i0] = sl[column].to_numpy()
    lo = grid_corner(df, edge)
    x0, y0 = lo[0] + i0 * edge, lo[1] + j0 * edge
    return img, [x0, x0 + nx * edge, y0, y0 + ny * edge]
