"""The capacity map for people: how much of the workspace carries the task payloads, where on the plane through
the task's start and goal, and the paths around the task (each verified along its own direction, so it can carry
more than the voxels it crosses, whose value is their least over every direction)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import patheffects

from capmap.plots.capacity_cuts import hatch_zero, mark_ends, plane_cut, volume
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


def _notes(ax, project, paths) -> None:
    """Each path's note (why it holds where the voxels say less) in a box at the top left of the right panel,
    an arrow to the middle of the path."""
    y = 0.97
    for _, xyz, style, note in [p for p in paths if len(p) > 3 and p[3]]:
        h, v, _ = project(xyz)
        mid = len(h) // 2
        ax.annotate(note, (h[mid], v[mid]), xytext=(0.03, y), textcoords="axes fraction", va="top", fontsize=9.5,
                    bbox=dict(fc="white", ec=style.get("color", "black"), lw=2, alpha=0.92, pad=4), zorder=14,
                    arrowprops=dict(arrowstyle="->", color=style.get("color", "black"), lw=1.8))
        y -= 0.16


def _map_panels(axes, main: pd.DataFrame, view, paths, vmax: float):
    """The middle and right panels: the map's voxels on the vertical plane through start and goal, 0 kg
    hatched, the payloads' contours labelled in view, the paths, start and goal; the right panel zoomed on the
    task. Returns the image artist, the payloads drawn as contours and how far off the plane the paths run."""
    grid = main.attrs["capmap"]["grid"]
    cap = main.capacity_kg.to_numpy()
    img, extent, project = plane_cut(volume(main, cap), grid, view.start_m, view.goal_m)
    levels = [m for m in view.payloads_kg if np.nanmin(img, initial=np.inf) < m <= np.nanmax(img, initial=-np.inf)]
    task = np.vstack([np.column_stack(project(np.asarray(x, float).reshape(-1, 3))[:2])
                      for x in [view.start_m, view.goal_m] + [p[1] for p in paths]])
    rows, cols = np.flatnonzero(np.isfinite(img).any(axis=1)), np.flatnonzero(np.isfinite(img).any(axis=0))
    h, v = np.linspace(*extent[:2], img.shape[1] + 1), np.linspace(*extent[2:], img.shape[0] + 1)
    lo_t, hi_t = task.min(axis=0) - 4 * grid["edge_m"], task.max(axis=0) + 4 * grid["edge_m"]
    views = [((h[cols[0]], h[cols[-1] + 1]), (v[rows[0]], v[rows[-1] + 1])) if len(rows) else (None, None),
             ((lo_t[0], hi_t[0]), (lo_t[1], hi_t[1]))]
    off = 0.0
    for ax, (xlim, ylim) in zip(axes, views):
        im = ax.imshow(img, origin="lower", cmap="viridis", vmin=0.0, vmax=vmax, extent=extent, interpolation="nearest")
        hatch_zero(ax, img == 0, extent, HATCH, label=ax is axes[1])
        for name, xyz, style, *_ in paths:
            hp, vp, o = project(np.asarray(xyz, float).reshape(-1, 3))
            off = max(off, float(np.max(o, initial=0.0)))
            ax.plot(hp, vp, lw=3 if style.get("ls", "-") == "-" else 2.2, label=name, zorder=10, **style)
        mark_ends(ax, project, view.start_m, view.goal_m)
        ax.set(xlabel="horizontal distance from the start towards the goal [m]", ylabel="height z [m]", aspect="equal",
               xlim=xlim, ylim=ylim)
        if levels:
            cs = ax.contour(np.where(np.isnan(img), -1.0, img), levels=levels, colors="white", linewidths=1.8,
                            extent=extent, origin="lower")
            _levels_labelled(ax, cs, img, extent, task)
    _notes(axes[1], project, paths)
    return im, levels, off


def capacity_map(vox: pd.DataFrame, view, out_png: str | Path, op: pd.DataFrame | None = None,
                 configuration: str = "", paths=()) -> None:
    """The map for people. Left, how much: the share of the reachable voxels that carry a payload M on the
    arm's ``configuration`` (``op``, :func:`capmap.capacity.tables.configuration_voxels`) and for any
    configuration (the all-branch bound ``vox``). Middle, where: that map's voxels on the vertical plane
    through the task's start and goal (both on it), coloured by capacity (the least over the voxel's points
    and every motion direction), the task payloads as labelled contours, 0 kg voxels hatched (every one); right,
    the same plane around the task (the box in the middle panel, named) with ``paths`` ((label, (n, 3) m, plot
    style[, note]) each; a label says what the path itself carries along its own direction, a note, written in
    a box with an arrow to the path, why it holds across voxels of less). ``view``: a
    :class:`capmap.stages.capacity_figures.MapView` (start_m, goal_m, payloads_kg)."""
    main = vox if op is None else op
    which = f"configuration {configuration} (the arm's)" if op is not None else "any configuration"
    grid = vox.attrs["capmap"]["grid"]
    fig, axes = plt.subplots(1, 3, figsize=(19, 8.0), width_ratios=[0.85, 1.1, 1.1], layout="constrained")
    _share_panel(axes[0], main, vox if op is not None else None, which, view.payloads_kg, grid["edge_m"])
    cap = main.capacity_kg.to_numpy()
    vmax = float(np.nanmax(np.r_[cap[main.n_reachable > 0], 1.0]))
    im, levels, off = _map_panels(axes[1:], main, view, list(paths), vmax)
    box = axes[1].indicate_inset_zoom(axes[2], edgecolor="black", lw=1.6, alpha=1.0)
    x0, y1 = box.rectangle.get_x(), box.rectangle.get_y() + box.rectangle.get_height()
    axes[1].annotate("right panel", (x0, y1), xytext=(2, 3), textcoords="offset points", fontsize=9, weight="bold",
                     bbox=dict(fc="white", ec="black", lw=1, pad=1.5), zorder=13)
    missing = [f"{m:g} kg" for m in view.payloads_kg if m not in levels]
    carried = [f"white lines: {', '.join(f'{m:g} kg' for m in levels)} carried in every direction"] if levels else []
    axes[1].set_title("\n".join(["Where: vertical plane through start and goal",
                                 "colour: each voxel's capacity, its least over EVERY direction",
                                 "; ".join(carried + [f"{', '.join(missing)}: no voxel here"] * bool(missing))]),
                      fontsize=10.5)
    axes[2].set_title("Around the task: a path is verified along ITS OWN direction,\nso it can carry more than the "
                      "voxels it crosses" + (f"\n(paths drawn on the plane, {off:.2f} m off it at most)"
                                             if off > 0.05 * grid["edge_m"] else ""), fontsize=10.5, weight="bold")
    cb = fig.colorbar(im, ax=axes[1:], shrink=0.8, label="voxel capacity [kg]: least over its points and every "
                                                          "direction (hatched: exactly 0 kg)")
    for m in [m for m in view.payloads_kg if m <= vmax]:
        cb.ax.axhline(m, color="white", lw=2)
    handles = axes[2].get_legend_handles_labels()[0]
    if levels:
        handles.insert(1, plt.Line2D([], [], color="white", lw=1.8, label=f"white line: {', '.join(f'{m:g}' for m in levels)}"
                                     " kg carried in every direction (the lighter side)",
                                     path_effects=[patheffects.Stroke(linewidth=3.6, foreground="0.35"),
                                                   patheffects.Normal()]))
    axes[2].legend(handles=handles, fontsize=8.5, loc="upper center", bbox_to_anchor=(0.5, -0.1))
    fig.suptitle(f"Dynamic load-carrying capacity of the locked arm on {which}: how much of the workspace, and where, "
                 "carries the task payloads", fontsize=13)
    save(fig, out_png)


def _share_panel(ax, main: pd.DataFrame, bound: pd.DataFrame | None, which: str, payloads, edge: float) -> None:
    """The share of the reachable voxels carrying M, against M, on ``main`` and (dashed) the ``bound``."""
    curves = [(which, main, dict(color="tab:blue", lw=2))]
    if bound is not None:
        curves.append(("any configuration (the bound: least over every IK branch)", bound,
                       dict(color="0.35", ls="--", lw=1.5)))
    top = max([float(np.nanmax(np.r_[m.capacity_kg[m.n_reachable > 0], 0.0])) for _, m, _ in curves] + list(payloads))
    grid_m = np.linspace(0.0, 1.05 * top, 500)
    shares = []
    for label, m, style in curves:
        c = np.sort(m.capacity_kg[m.n_reachable > 0].to_numpy())
        ax.plot(grid_m, 100 * (len(c) - np.searchsorted(c, grid_m)) / max(len(c), 1), label=label, **style)
        shares.append([100 * float(np.mean(c >= p)) if len(c) else 0.0 for p in payloads])
    for n, p in enumerate(payloads):
        ax.axvline(p, color="0.2", ls=":", lw=1)
        text = f"{p:g} kg: {shares[0][n]:.0f} %" + (f" ({shares[1][n]:.0f} % any)" if len(shares) > 1 else "")
        ax.text(p, 97 - 8 * n, " " + text + " ", fontsize=9, va="top", ha="right" if p > 0.6 * top else "left",
                bbox=dict(fc="white", ec="none", alpha=0.85))
    n_reach = int((main.n_reachable > 0).sum())
    ax.set(xlabel="payload M [kg]", ylabel="reachable voxels carrying M in every direction [%]", ylim=(0, 100),
           xlim=(0, 1.05 * top))
    ax.set_title(f"How much: {n_reach:,} voxels reached ({n_reach * edge ** 3:,.0f} m³, edge {edge:g} m)", fontsize=10.5)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8.5, loc="upper center", bbox_to_anchor=(0.5, -0.1))
