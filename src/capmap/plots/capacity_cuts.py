"""Planes through the capacity map, shared by its figures: a voxel map as a volume, its cut on the vertical
plane through two points (or on a horizontal layer), the 0 kg cells hatched cell by cell, a task's start
and goal marked, and a path drawn in its own colour around a core coloured by its own capacity."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib import colormaps, patheffects
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

__all__ = ["volume", "plane_cut", "hatch_zero", "mark_ends", "cased_path", "unreached_handle", "ENDS", "ZERO_LABEL",
           "CMAP"]

ENDS = {"start": dict(marker="o", ms=10), "goal": dict(marker="*", ms=15)}  # white, black edge: on any colour
ZERO_LABEL = "0 kg voxel (singular surface), hatched"
CMAP = "viridis"  # capacity, voxels and paths alike
CASING, CORE = 6.5, 3.0  # a path's line widths: its own colour around, its capacity inside


def volume(m: pd.DataFrame, values: np.ndarray) -> np.ndarray:
    """(nx, ny, nz) array of ``values`` (one per row of the map ``m``) on its grid, NaN where not reached."""
    vol = np.full(m.attrs["capmap"]["grid"]["shape"], np.nan)
    r = (m.n_reachable > 0).to_numpy()
    vol[m.i.to_numpy()[r], m.j.to_numpy()[r], m.k.to_numpy()[r]] = np.asarray(values, float)[r]
    return vol


def plane_cut(vol: np.ndarray, grid: dict, a: np.ndarray, b: np.ndarray, layer_z: float | None = None):
    """The values of ``vol`` on a plane: the vertical plane through ``a`` and ``b`` (abscissa u: the distance
    from a along a->b's horizontal direction, ordinate z), or the horizontal layer holding ``layer_z`` (x, y).
    Returns the image, its imshow extent and project(xyz (n, 3)) -> (abscissa, ordinate, distance off the plane)."""
    dx, lo, shape = grid["edge_m"], np.asarray(grid["lower_m"], float), np.asarray(grid["shape"])
    if layer_z is not None:
        k = int(np.clip(np.floor((layer_z - lo[2]) / dx), 0, shape[2] - 1))
        zc = lo[2] + (k + 0.5) * dx
        return (vol[:, :, k].T, [lo[0], lo[0] + shape[0] * dx, lo[1], lo[1] + shape[1] * dx],
                lambda p: (p[:, 0], p[:, 1], np.abs(p[:, 2] - zc)))
    d = (b - a)[:2]
    d = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-9 else np.array([1.0, 0.0])
    n = np.array([-d[1], d[0]])
    reach = np.linalg.norm(shape[:2] * dx) + np.linalg.norm(a[:2] - lo[:2])  # beyond the grid: cropped by the caller
    u = np.arange(-reach, reach, dx / 2) + dx / 4
    z = lo[2] + np.arange(0, shape[2] * dx, dx / 2) + dx / 4
    U, Z = np.meshgrid(u, z)
    idx = np.floor((np.dstack([a[:2] + U[..., None] * d, Z]) - lo) / dx).astype(int)
    ok = np.all((idx >= 0) & (idx < shape), axis=-1)
    img = np.full(U.shape, np.nan)
    img[ok] = vol[idx[ok][:, 0], idx[ok][:, 1], idx[ok][:, 2]]
    return (img, [u[0] - dx / 4, u[-1] + dx / 4, z[0] - dx / 4, z[-1] + dx / 4],
            lambda p: ((p[:, :2] - a[:2]) @ d, p[:, 2], np.abs((p[:, :2] - a[:2]) @ n)))


def hatch_zero(ax, zero: np.ndarray, extent, colour: str = "0.2", label: bool = True) -> None:
    """Hatch every cell of a cut (image ``zero`` of booleans, its imshow ``extent``) where the voxel's least
    over every direction is 0 kg, each cell whole (a contour would shrink the cells at the map's edge);
    ``colour`` of the hatch; ``label``: a legend entry for it."""
    if not np.any(zero):
        return
    h = np.linspace(extent[0], extent[1], zero.shape[1] + 1)
    v = np.linspace(extent[2], extent[3], zero.shape[0] + 1)
    ax.pcolor(h, v, np.ma.masked_where(~zero, np.ones(zero.shape)), hatch="xxx", facecolor="none", edgecolor=colour,
              lw=0, zorder=2)
    if label:
        ax.fill([], [], fc="0.35" if colour != "0.2" else "none", ec=colour, hatch="xxx", label=ZERO_LABEL)


def mark_ends(ax, project, start: np.ndarray, goal: np.ndarray) -> None:
    """The start (circle) and goal (star), white with a black edge, named beside them."""
    for name, pos in (("start", start), ("goal", goal)):
        h, v, _ = project(np.atleast_2d(pos))
        ax.plot(h, v, ls="none", mfc="white", mec="black", mew=1.5, zorder=12, **ENDS[name])
        ax.annotate(name, (h[0], v[0]), xytext=(7, 7), textcoords="offset points", fontsize=9, weight="bold",
                    bbox=dict(fc="white", ec="none", alpha=0.8, pad=1), zorder=12)


def cased_path(ax, h: np.ndarray, v: np.ndarray, kg: np.ndarray | None, norm, casing: str,
               label: str | None = None) -> Line2D:
    """A path (h, v) drawn thick in its own ``casing`` colour with a core coloured by its own capacity ``kg`` (one
    value per piece i -> i + 1, n - 1 of them; NaN: casing only) on the capacity scale ``norm``; without ``kg``,
    the casing alone (thinner). Returns its legend handle (its least capacity's colour inside its colour)."""
    ax.plot(h, v, color=casing, lw=CASING if kg is not None else 3.0, solid_capstyle="round", zorder=10)
    if kg is None:
        return Line2D([], [], color=casing, lw=3.0, label=label)
    kg = np.asarray(kg, float)
    pts = np.column_stack([h, v])
    ok = np.isfinite(kg)
    segs = np.stack([pts[:-1], pts[1:]], axis=1)[ok]
    ax.add_collection(LineCollection(segs, array=kg[ok], cmap=CMAP, norm=norm, lw=CORE, capstyle="round",
                                     zorder=10.2))
    colour = colormaps[CMAP](norm(np.nanmin(kg))) if ok.any() else casing
    return Line2D([], [], color=colour, lw=CORE, label=label,
                  path_effects=[patheffects.Stroke(linewidth=CASING, foreground=casing), patheffects.Normal()])


def unreached_handle() -> Patch:
    """The legend entry of a map's white cells."""
    return Patch(fc="white", ec="0.5", label="not reached (white)")
