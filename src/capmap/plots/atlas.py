"""Figures of the fault atlas: heat maps over (locked joint x lock angle) and the
capacity-volume curves of every map."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import plt, save

__all__ = ["atlas_heatmap", "atlas_curves_figure"]


def _grid(df: pd.DataFrame, column: str, joints, angles) -> np.ndarray:
    img = np.full((len(joints), len(angles)), np.nan)
    for _, r in df.iterrows():
        img[joints.index(r.joint), angles.index(r.angle_deg)] = r[column]
    return img


def _panel(fig, ax, img, joints, angles, title, label, cmap="viridis", marks=None, vmax=None):
    """One heat map over (locked joint, lock angle), each cell's value written (with ``marks`` under it)."""
    finite = img[np.isfinite(img)]
    vmax = vmax if vmax is not None else (float(finite.max()) if len(finite) else 1.0)
    im = ax.imshow(img, origin="lower", aspect="auto", cmap=cmap, vmin=0.0, vmax=vmax or 1.0)
    fig.colorbar(im, ax=ax, label=label)
    ax.set_xticks(range(len(angles)), [f"{a:g}" for a in angles])
    ax.set_yticks(range(len(joints)), [str(j) for j in joints])
    ax.set(xlabel="lock angle [deg]", ylabel="locked joint", title=title)
    for (r, c), v in np.ndenumerate(img):
        text = "not\nreachable" if not np.isfinite(v) else f"{v:,.0f}"
        if marks is not None and np.isfinite(v):
            text += "\n" + marks[r][c]
        dark = np.isfinite(v) and v / (vmax or 1.0) < 0.5  # both maps are dark at their low end
        ax.text(c, r, text, ha="center", va="center", fontsize=8, color="white" if dark else "black")


def atlas_heatmap(atlas: pd.DataFrame, out_png: str | Path) -> None:
    """Per (joint, angle): reachable volume, median voxel capacity, and for each task payload the
    volume that carries it (on the same colour scale as the reachable volume), marked "plan + direct",
    "plan" (the planner finds a path), "direct" (the direct line carries it) or "no path"; the title names
    the lock that keeps the most and the least volume carrying each payload."""
    joints = sorted(atlas.joint.unique().tolist())
    angles = sorted(atlas.angle_deg.unique().tolist())
    payloads = sorted(atlas.payload_kg.unique().tolist())
    first = atlas[atlas.payload_kg == payloads[0]]
    n = 2 + len(payloads)
    fig, axes = plt.subplots(1, n, figsize=(4.4 * n, 0.5 * len(joints) + 3.6), layout="constrained")
    reach = _grid(first, "reachable_volume_m3", joints, angles)
    top = float(np.nanmax(reach, initial=1.0))
    _panel(fig, axes[0], reach, joints, angles, "reachable at the task orientation", "volume [m³]", vmax=top)
    _panel(fig, axes[1], _grid(first, "capacity_median_kg", joints, angles), joints, angles,
           "median voxel capacity", "capacity [kg]", cmap="magma")
    best = []
    for ax, m in zip(axes[2:], payloads):
        sub = atlas[atlas.payload_kg == m]
        marks = [["" for _ in angles] for _ in joints]
        for _, r in sub.iterrows():
            marks[joints.index(r.joint)][angles.index(r.angle_deg)] = (
                " + ".join(w for w, ok in (("plan", r.plan_exists), ("direct", r.direct_feasible)) if ok) or "no path")
        _panel(fig, ax, _grid(sub, "volume_carrying_payload_m3", joints, angles), joints, angles,
               f"volume carrying {m:g} kg; the task's start to goal:\nplan (a planned path) / direct (the direct "
               "line carries it)", "volume [m³]", marks=marks, vmax=top)
        hi, lo = sub.loc[sub.volume_carrying_payload_m3.idxmax()], sub.loc[sub.volume_carrying_payload_m3.idxmin()]
        best.append(f"{m:g} kg: most with joint {hi.joint} at {hi.angle_deg:g} deg ({hi.volume_carrying_payload_m3:,.0f} m³),"
                    f" least with joint {lo.joint} at {lo.angle_deg:g} deg ({lo.volume_carrying_payload_m3:,.0f} m³)")
    fig.suptitle("Fault atlas: one coarse capacity map per locked joint and lock angle\n" + "; ".join(best), fontsize=11.5)
    save(fig, out_png)


def atlas_curves_figure(curves: pd.DataFrame, payloads: list[float], out_png: str | Path) -> None:
    """Capacity-volume curves: one panel per locked joint, one line per lock angle (the legend beside the
    panels); the task payloads as dashed vertical lines, labelled."""
    joints = sorted(curves.joint.unique().tolist())
    cols = min(4, len(joints))
    rows = int(np.ceil(len(joints) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols + 1.6, 3.2 * rows + 0.6), sharex=True, sharey=True,
                             squeeze=False, layout="constrained")
    angles = sorted(curves.angle_deg.unique().tolist())
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, len(angles)))
    for ax, j in zip(axes.flat, joints):
        for a, c in zip(angles, colours):
            s = curves[(curves.joint == j) & (curves.angle_deg == a)]
            ax.plot(s.payload_kg, s.volume_m3, color=c, label=f"{a:g} deg")
        for m in payloads:
            ax.axvline(m, color="0.4", ls="--", lw=0.8)
            ax.text(m, 0.98, f" {m:g} kg", transform=ax.get_xaxis_transform(), fontsize=7.5, color="0.3", va="top")
        ax.set_title(f"joint {j} locked")
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("payload M [kg]")
    for ax in axes[:, 0]:
        ax.set_ylabel("volume carrying ≥ M [m³]")
    for ax in list(axes.flat)[len(joints):]:
        ax.axis("off")
    fig.legend(*axes.flat[0].get_legend_handles_labels(), title="lock angle", fontsize=8, loc="outside right center")
    fig.suptitle("Capacity-volume curves: the volume whose voxels carry at least M, per locked joint and lock angle")
    save(fig, out_png)
