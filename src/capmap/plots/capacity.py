"""The capacity map for people: how much of the workspace carries the task payloads, where on the plane through
the task's start and goal, and the paths around the task, each coloured by its own capacity (verified along its own
direction, so it can carry more than the voxels it crosses, whose value is their least over every direction)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import patheffects
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from capmap.plots.capacity_cuts import CMAP, ZERO_LABEL, cased_path, hatch_zero, mark_ends, plane_cut, unreached_handle, volume
from capmap.plots.common import plt, save

__all__ = ["capacity_map"]

HATCH = "0.8"  # the 0 kg cells' hatch: light, to read on the dark end of viridis


def _levels_labelled(ax, cs, img: np.ndarray, extent, avoid: np.ndarray) -> None:
    """Label each contour of ``cs`` once: inside the axes' view (not at its edge), where the cut ``img`` (its
    imshow ``extent``) is reached and above 0 kg for a voxel around (not on a hatched or white cell), and as far
    as it can from the ``avoid`` points (n, 2) (the task's start, goal and paths)."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    mx, my = 0.1 * (x1 - x0), 0.08 * (y1 - y0)
    clear = np.nan_to_num(img, nan=0.0) > 0
    for shift in ((0, 1), (0, -1), (1, 0), (-1, 0), (0, 2), (0, -2), (2, 0), (-2, 0)):  # a voxel around (2 cells)
        clear &= np.roll(np.nan_to_num(img, nan=0.0) > 0, shift, axis=(0, 1))
    for level, segs in zip(cs.levels, cs.allsegs):
        pts = np.vstack([s for s in segs if len(s)] or [np.empty((0, 2))])
        pts = pts[(pts[:, 0] > x0 + mx) & (pts[:, 0] < x1 - mx) & (pts[:, 1] > y0 + my) & (pts[:, 1] < y1 - my)]
        col = np.clip(((pts[:, 0] - extent[0]) / (extent[1] - extent[0]) * img.shape[1]).astype(int), 0, img.shape[1] - 1)
        row = np.clip(((pts[:, 1] - extent[2]) / (extent[3] - extent[2]) * img.shape[0]).astype(int), 0, img.shape[0] - 1)
        pts = pts[clear[row, col]]
        if len(pts):
            far = np.min(np.linalg.norm(pts[:, None] - avoid[None], axis=2), axis=1) if len(avoid) else np.ones(len(pts))
            ax.clabel(cs, levels=[level], manual=[tuple(pts[int(np.argmax(far))])], fmt=lambda m: f"{m:g} kg",
                      fontsize=9.5)


def _map_panels(axes, main: pd.DataFrame, view, paths, norm):
    """The middle and right panels: the map's voxels on the vertical plane through start and goal, 0 kg
    hatched, the payloads' contours labelled in view, start and goal; the paths thin in their colours in the
    middle, coloured by their own capacity (:func:`cased_path`) on the right, zoomed on the task. Returns the
    image artist, the payloads drawn as contours and the paths' legend handles."""
    grid = main.attrs["capmap"]["grid"]
    img, extent, project = plane_cut(volume(main, main.capacity_kg.to_numpy()), grid, view.start_m, view.goal_m)
    levels = [m for m in view.payloads_kg if np.nanmin(img, initial=np.inf) < m <= np.nanmax(img, initial=-np.inf)]
    task = np.vstack([np.column_stack(project(np.asarray(x, float).reshape(-1, 3))[:2])
                      for x in [view.start_m, view.goal_m] + [p[1] for p in paths]])
    rows, cols = np.flatnonzero(np.isfinite(img).any(axis=1)), np.flatnonzero(np.isfinite(img).any(axis=0))
    h, v = np.linspace(*extent[:2], img.shape[1] + 1), np.linspace(*extent[2:], img.shape[0] + 1)
    lo_t, hi_t = task.min(axis=0) - 2.5 * grid["edge_m"], task.max(axis=0) + 2.5 * grid["edge_m"]
    views = [((h[cols[0]], h[cols[-1] + 1]), (v[rows[0]], v[rows[-1] + 1])) if len(rows) else (None, None),
             ((lo_t[0], hi_t[0]), (lo_t[1], hi_t[1]))]
    handles = []
    for ax, (xlim, ylim) in zip(axes, views):
        im = ax.imshow(img, origin="lower", cmap=CMAP, norm=norm, extent=extent, interpolation="nearest")
        hatch_zero(ax, img == 0, extent, HATCH, label=False)
        for name, xyz, style, kg in paths:
            hp, vp, _ = project(np.asarray(xyz, float).reshape(-1, 3))
            handles.append(cased_path(ax, hp, vp, kg if ax is axes[1] else None, norm, style["color"], name))
        mark_ends(ax, project, view.start_m, view.goal_m)
        ax.set(xlabel="horizontal distance from the start towards the goal [m]", ylabel="height z [m]", aspect="equal",
               xlim=xlim, ylim=ylim)
        if levels:
            cs = ax.contour(np.where(np.isnan(img), -1.0, img), levels=levels, colors="white", linewidths=1.8,
                            extent=extent, origin="lower")
            _levels_labelled(ax, cs, img, extent, task)
    return im, levels, handles[len(paths):]


def _map_legend(ax, levels: list[float], payloads) -> None:
    """The map's legend under the middle panel: the 0 kg hatch, the white (not reached) cells, the contours."""
    handles = [Patch(fc="0.35", ec=HATCH, hatch="xxx", label=ZERO_LABEL), unreached_handle()]
    missing = [f"{m:g} kg" for m in payloads if m not in levels]
    if levels:
        handles.append(Line2D([], [], color="white", lw=1.8, path_effects=[patheffects.Stroke(linewidth=3.6,
                                                                                              foreground="0.35"),
                                                                           patheffects.Normal()],
                              label=f"white line: {', '.join(f'{m:g}' for m in levels)} kg in every direction"
                              + (f" ({', '.join(missing)}: none here)" if missing else "")))
    ax.legend(handles=handles, fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.1))


def capacity_map(vox: pd.DataFrame, view, out_png: str | Path, op: pd.DataFrame | None = None,
                 configuration: str = "", paths=(), verdict: str = "") -> None:
    """The map for people. Left, how much: the share of the reachable voxels that carry a payload M on the
    arm's ``configuration`` (``op``, :func:`capmap.capacity.tables.configuration_voxels`) and for any
    configuration (the all-branch bound ``vox``), the 0 kg voxels' share written. Middle, where: that map's
    voxels on the vertical plane through the task's start and goal, coloured by capacity (the least over the
    voxel's points and every motion direction), the task payloads as labelled contours, 0 kg voxels hatched
    (every one); right, the same plane around the task (the box in the middle panel, named) with ``paths``
    ((label, (n, 3) m, plot style with its "color", the capacity of each of its n - 1 pieces along its own
    direction kg or None) each), each drawn in its colour around a core coloured by its own capacity on the
    voxels' scale. The headline: each payload's share and ``verdict`` (the paths', in words). ``view``: a
    :class:`capmap.stages.capacity_figures.MapView` (start_m, goal_m, payloads_kg)."""
    main = vox if op is None else op
    which = f"{configuration} (the arm's configuration)" if op is not None else "any configuration"
    grid = vox.attrs["capmap"]["grid"]
    fig, axes = plt.subplots(1, 3, figsize=(19, 7.6), width_ratios=[0.85, 1.1, 1.1], layout="constrained")
    name = f"{configuration} (the arm's)" if op is not None else which
    shares = _share_panel(axes[0], main, vox if op is not None else None, name, view.payloads_kg, grid["edge_m"])
    cap = main.capacity_kg.to_numpy()
    vmax = float(np.nanmax(np.r_[cap[main.n_reachable > 0], 1.0]))
    paths = list(paths)
    im, levels, handles = _map_panels(axes[1:], main, view, paths, Normalize(0.0, vmax))
    box = axes[1].indicate_inset_zoom(axes[2], edgecolor="black", lw=1.6, alpha=1.0)
    for line in box.connectors:  # the box is named: no lines across the map
        line.set_visible(False)
    x0, y1 = box.rectangle.get_x(), box.rectangle.get_y() + box.rectangle.get_height()
    axes[1].annotate("right panel", (x0, y1), xytext=(2, 3), textcoords="offset points", fontsize=9, weight="bold",
                     bbox=dict(fc="white", ec="black", lw=1, pad=1.5), zorder=13)
    axes[1].set_title("Where: vertical plane through start and goal", fontsize=11)
    axes[2].set_title("Around the task: each path coloured by its own capacity", fontsize=11)
    over = any(kg is not None and np.nanmax(kg, initial=0.0) > vmax for *_, kg in paths)
    cb = fig.colorbar(im, ax=axes[1:], shrink=0.8, extend="max" if over else "neither", label="capacity [kg]")
    for m in [m for m in view.payloads_kg if m <= vmax]:
        cb.ax.axhline(m, color="white", lw=2)
    _map_legend(axes[1], levels, view.payloads_kg)
    axes[2].legend(handles=handles, fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.1))
    carry = ", ".join(f"{s:.0f} % carry {m:g} kg" for m, s in zip(view.payloads_kg, shares))
    fig.suptitle(f"On {which}, {carry.replace(' carry', ' of the reachable voxels carry', 1)}"
                 + (f"; {verdict}" if verdict else ""), fontsize=13)
    save(fig, out_png)


def _share_panel(ax, main: pd.DataFrame, bound: pd.DataFrame | None, which: str, payloads, edge: float) -> list[float]:
    """The share of the reachable voxels carrying M > 0, against M, on ``main`` and (dashed) the ``bound``; the
    0 kg voxels' share as a hatched bar above the curves' start. Returns each payload's share on ``main`` [%]."""
    curves = [(which, main, dict(color="tab:blue", lw=2))]
    if bound is not None:
        curves.append(("any configuration (the bound)", bound, dict(color="0.35", ls="--", lw=1.5)))
    top = max([float(np.nanmax(np.r_[m.capacity_kg[m.n_reachable > 0], 0.0])) for _, m, _ in curves] + list(payloads))
    grid_m = np.r_[1e-9, np.linspace(0.0, 1.05 * top, 500)[1:]]  # M > 0: the 0 kg voxels apart
    shares, zero = [], []
    for label, m, style in curves:
        c = np.sort(m.capacity_kg[m.n_reachable > 0].to_numpy())
        ax.plot(grid_m, 100 * (len(c) - np.searchsorted(c, grid_m)) / max(len(c), 1), label=label, **style)
        shares.append([100 * float(np.mean(c >= p)) if len(c) else 0.0 for p in payloads])
        zero.append(100 * float(np.mean(c <= 0)) if len(c) else 0.0)
    ax.bar(0.0, zero[0], bottom=100 - zero[0], width=0.025 * top, align="edge", fc="0.35", ec=HATCH, hatch="xxx",
           lw=0)
    ax.annotate(f"0 kg voxels: {zero[0]:.0f} %" + (f" ({zero[1]:.0f} % any)" if len(zero) > 1 else ""),
                (0.025 * top, 100 - zero[0] / 2), xytext=(6, 0), textcoords="offset points", va="center", fontsize=9.5)
    for n, p in enumerate(payloads):
        ax.axvline(p, color="0.2", ls=":", lw=1)
        ax.text(p, 97 - 8 * n, f" {p:g} kg: {shares[0][n]:.0f} % ", fontsize=9.5, va="top",
                ha="right" if p > 0.6 * top else "left", bbox=dict(fc="white", ec="none", alpha=0.85))
    n_reach = int((main.n_reachable > 0).sum())
    ax.set(xlabel="payload M [kg]", ylabel="reachable voxels carrying M in every direction [%]", ylim=(0, 101),
           xlim=(0, 1.05 * top))
    ax.set_title(f"How much: {n_reach:,} voxels reached ({n_reach * edge ** 3:,.0f} m³)", fontsize=11)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.1))
    return shares[0]
