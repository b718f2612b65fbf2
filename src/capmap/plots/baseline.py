"""Figure of the healthy-arm baseline: what the failure cost, per payload and per voxel."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import plt, save

__all__ = ["BaselineContext", "baseline_figure"]


@dataclass(frozen=True)
class BaselineContext:
    """What the baseline's figure tells of its run: the arm's configuration (its name); the failed
    ``joint`` (1-based) locked at angle_deg deg; the healthy map's angle step step_deg deg; the voxel
    edge edge_m m; the task start start_m (3,) m; the task's payloads_kg (kg each)."""

    configuration: str
    joint: int
    angle_deg: float
    step_deg: float
    edge_m: float
    start_m: np.ndarray
    payloads_kg: tuple[float, ...]


def _lower(df: pd.DataFrame, edge: float) -> np.ndarray:
    """(3,) m: the corner of voxel (0, 0, 0) of the table's grid (centre = lower + (index + 1/2) edge)."""
    r = df.iloc[0]
    return np.array([r.x_m, r.y_m, r.z_m]) - (np.array([r.i, r.j, r.k], dtype=float) + 0.5) * edge


def _layer(df: pd.DataFrame, column: str, k: int, edge: float) -> tuple[np.ndarray, list[float]]:
    """Image (ny, nx) of ``column`` over the voxel layer k (NaN: no value) and its imshow extent [m]."""
    i0, j0 = int(df.i.min()), int(df.j.min())
    nx, ny = int(df.i.max()) - i0 + 1, int(df.j.max()) - j0 + 1
    img = np.full((ny, nx), np.nan)
    sl = df[df.k == k]
    img[sl.j.to_numpy() - j0, sl.i.to_numpy() - i0] = sl[column].to_numpy()
    lo = _lower(df, edge)
    x0, y0 = lo[0] + i0 * edge, lo[1] + j0 * edge
    return img, [x0, x0 + nx * edge, y0, y0 + ny * edge]


def baseline_figure(df: pd.DataFrame, conv: pd.DataFrame, context: BaselineContext, out_png: str | Path) -> None:
    """Four panels: the volume carrying each payload, healthy and failed (the arm's configuration and
    any); the start's voxel layer of the healthy map and of the loss on the arm's configuration; the rise
    of the checked voxels' healthy values at half and a quarter of the angle step."""
    configuration, joint, angle_deg, step_deg = context.configuration, context.joint, context.angle_deg, context.step_deg
    edge_m, start_m, payloads_kg = context.edge_m, context.start_m, context.payloads_kg
    fig, ax = plt.subplots(2, 2, figsize=(13, 10.5))
    a = ax[0, 0]
    top = np.nanmax(df.healthy_capacity_kg.to_numpy(), initial=1.0)
    m = np.linspace(0.0, top * 1.02, 400)
    for col, label, style in (("healthy_capacity_kg", "healthy arm (best self-motion)", dict(color="black")),
                              ("arm_configuration_capacity_kg", f"failed, on the arm's configuration {configuration}",
                               dict(color="tab:blue")),
                              ("capacity_kg", "failed, any configuration (the bound)", dict(color="tab:blue", ls="--"))):
        v = np.sort(df[col].dropna().to_numpy())
        if len(v):
            a.plot(m, (len(v) - np.searchsorted(v, m, side="left")) * edge_m**3, label=label, **style)
    for p in payloads_kg:
        a.axvline(p, color="gray", ls=":", lw=1)
        a.text(p, a.get_ylim()[1] * 0.97, f" {p:g} kg", color="gray", fontsize=8, va="top")
    a.set(xlabel="payload M [kg]", ylabel="volume of voxels carrying M [m³]",
          title=f"What the failure of joint {joint} (locked at {angle_deg:g} deg) cost")
    a.legend(fontsize=8)
    lo = _lower(df, edge_m)
    k = int(np.floor((start_m[2] - lo[2]) / edge_m))  # the task start's layer
    z = lo[2] + (k + 0.5) * edge_m
    for a, col, title, cmap in ((ax[0, 1], "healthy_capacity_kg", "healthy arm's capacity", "viridis"),
                                (ax[1, 0], "arm_configuration_loss_kg",
                                 f"loss on {configuration}: healthy − failed (failed 0 where it does not reach)", "magma_r")):
        img, extent = _layer(df, col, k, edge_m)
        im = a.imshow(img, origin="lower", cmap=cmap, extent=extent, interpolation="nearest",
                      vmin=0.0 if col == "healthy_capacity_kg" else None)
        fig.colorbar(im, ax=a, label=f"{'capacity' if col.startswith('healthy') else 'loss'} [kg]")
        if col != "healthy_capacity_kg":
            lost = df[(df.k == k) & df.capacity_kg.isna() & df.healthy_capacity_kg.notna()]
            a.plot(lost.x_m, lost.y_m, ".", color="tab:gray", ms=3,
                   label="the failed arm does not reach it (loss = healthy value)")
        neg = df[(df.k == k) & (df[col] < 0)]
        if len(neg):
            a.plot(neg.x_m, neg.y_m, "x", color="tab:cyan", ms=4, label="loss < 0 (reach differs inside the voxel)")
        a.plot(start_m[0], start_m[1], "o", ms=10, mfc="none", mec="tab:green", mew=2, label="task start")
        a.set(xlabel="x [m]", ylabel="y [m]", title=f"{title}\nlayer z = {z:.2f} m (the task start's)")
        a.legend(fontsize=7, loc="lower left")
    a = ax[1, 1]
    for col, label in (("rise_half_step_rel", f"{step_deg / 2:g} deg"), ("rise_quarter_step_rel", f"{step_deg / 4:g} deg")):
        v = np.sort(100 * conv[col].dropna().to_numpy())[::-1]
        a.plot(np.arange(1, len(v) + 1), v, marker=".", ms=3, label=f"angle step {label}")
    a.axhline(0.0, color="gray", lw=0.8)
    n = int(conv.rise_quarter_step_rel.notna().sum())
    a.set(xlabel="checked voxel (sorted by rise)", ylabel="rise of the healthy value over the step's [%]",
          title=f"Is a {step_deg:g} deg step of joint {joint} fine enough?\nworst points of {len(conv)} random voxels "
                f"({len(conv) - n} of 0 kg left out)")
    a.legend(fontsize=8)
    fig.suptitle("Healthy-arm baseline: the arm without the failure (best angle of the failed joint at each point) "
                 "against the failed arm", fontsize=11)
    save(fig, out_png, rect=(0, 0, 1, 0.97))
