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


def _panel(fig, ax, img, joints, angles, title, label, cmap="viridis", marks=None):
    im = ax.imshow(img, origin="lower", aspect="auto", cmap=cmap)
    fig.colorbar(im, ax=ax, label=label)
    ax.set_xticks(range(len(angles)), [f"{a:g}" for a in angles])
    ax.set_yticks(range(len(joints)), [str(j) for j in joints])
    ax.set(xlabel="lock angle [deg]", ylabel="locked joint", title=title)
    finite = img[np.isfinite(img)]
    mid = (finite.min() + finite.max()) / 2 if len(finite) else 0
    for (r, c), v in np.ndenumerate(img):
        text = "—" if not np.isfinite(v) else f"{v:.0f}"
        if marks is not None:
            text += "\n" + marks[r][c]
        ax.text(c, r, text, ha="center", va="center", fontsize=7,
                color="white" if np.isfinite(v) and v < mid else "black")


def atlas_heatmap(atlas: pd.DataFrame, out_png: str | Path) -> None:
    """Per (joint, angle): reachable volume, median voxel capacity, and for each task payload the
    volume that carries it, marked P (a plan exists) / D (the direct line carries it) / - (neither)."""
    joints = sorted(atlas.joint.unique().tolist())
    angles = sorted(atlas.angle_deg.unique().tolist())
    payloads = sorted(atlas.payload_kg.unique().tolist())
    first = atlas[atlas.payload_kg == payloads[0]]
    n = 2 + len(payloads)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 0.45 * len(joints) + 3.2))
    _panel(fig, axes[0], _grid(first, "reachable_volume_m3", joints, angles), joints, angles,
           "reachable at the task orientation", "volume [m³]")
    _panel(fig, axes[1], _grid(first, "capacity_median_kg", joints, angles), joints, angles,
           "median voxel capacity", "capacity [kg]", cmap="magma")
    for ax, m in zip(axes[2:], payloads):
        sub = atlas[atlas.payload_kg == m]
        marks = [["" for _ in angles] for _ in joints]
        for _, r in sub.iterrows():
            marks[joints.index(r.joint)][angles.index(r.angle_deg)] = (
                ("P" if r.plan_exists else "") + ("D" if r.direct_feasible else "")) or "-"
        _panel(fig, ax, _grid(sub, "volume_carrying_payload_m3", joints, angles), joints, angles,
               f"volume carrying {m:g} kg\n(P: plan exists, D: direct line carries it)", "volume [m³]", marks=marks)
    fig.suptitle("Fault atlas: one coarse capacity map per locked joint and lock angle (— : nothing reachable)")
    save(fig, out_png)


def atlas_curves_figure(curves: pd.DataFrame, payloads: list[float], out_png: str | Path) -> None:
    """Capacity-volume curves: one panel per locked joint, one line per lock angle; the task
    payloads as dashed vertical lines."""
    joints = sorted(curves.joint.unique().tolist())
    cols = min(4, len(joints))
    rows = int(np.ceil(len(joints) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), sharex=True, sharey=True, squeeze=False)
    angles = sorted(curves.angle_deg.unique().tolist())
    colours = plt.cm.tab10(np.arange(len(angles)) % 10)
    for ax, j in zip(axes.flat, joints):
        for a, c in zip(angles, colours):
            s = curves[(curves.joint == j) & (curves.angle_deg == a)]
            ax.plot(s.payload_kg, s.volume_m3, color=c, label=f"{a:g} deg")
        for m in payloads:
            ax.axvline(m, color="0.4", ls="--", lw=0.8)
        ax.set_title(f"joint {j} locked")
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("payload M [kg]")
    for ax in axes[:, 0]:
        ax.set_ylabel("volume carrying ≥ M [m³]")
    for ax in list(axes.flat)[len(joints):]:
        ax.axis("off")
    axes.flat[0].legend(title="lock angle", fontsize=7)
    fig.suptitle("Capacity-volume curves (dashed: task payloads)")
    save(fig, out_png)
