"""Figure of the healthy-arm baseline: what the failure cost, per payload and per voxel."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import grid_corner, plt, save, voxel_layer

__all__ = ["BaselineContext", "baseline_figure"]


@dataclass(frozen=True)
class BaselineContext:
    """What the baseline's figure tells of its run: the arm's configuration (its name); the failed
    ``joint`` (1-based) locked at angle_deg deg; the healthy map's angle step step_deg deg and the
    check's finer sweep check_step_deg deg; the voxel
    edge edge_m m; the task start start_m (3,) m; the task's payloads_kg (kg each)."""

    configuration: str
    joint: int
    angle_deg: float
    step_deg: float
    check_step_deg: float
    edge_m: float
    start_m: np.ndarray
    payloads_kg: tuple[float, ...]


def _volumes(a, df: pd.DataFrame, configuration: str, edge_m: float, payloads_kg) -> str:
    """The volume carrying each payload M, against M: healthy, failed on ``configuration``, failed for any
    configuration; each task payload marked. Returns the verdict at the task payloads (text)."""
    top = np.nanmax(df.healthy_capacity_kg.to_numpy(), initial=1.0)
    m = np.linspace(0.0, top * 1.02, 400)
    curves = (("healthy_capacity_kg", "healthy arm (best self-motion)", dict(color="black", lw=2)),
              ("arm_configuration_capacity_kg", f"failed, on the arm's configuration {configuration}",
               dict(color="tab:blue", lw=2)),
              ("capacity_kg", "failed, any configuration (the bound)", dict(color="tab:blue", ls="--")))
    vol = {}
    for col, label, style in curves:
        v = np.sort(df[col].dropna().to_numpy())
        vol[col] = lambda p, v=v: (len(v) - np.searchsorted(v, p, side="left")) * edge_m ** 3
        if len(v):
            a.plot(m, vol[col](m), label=label, **style)
    verdicts = []
    for n, p in enumerate(payloads_kg):
        h, f = vol["healthy_capacity_kg"](p), vol["arm_configuration_capacity_kg"](p)
        lost = f"{100 * (1 - f / h):.0f} %" if h > 0 else "—"
        verdicts.append(f"{p:g} kg: {h:,.0f} → {f:,.0f} m³ on {configuration} ({lost} lost)")
        a.axvline(p, color="0.3", ls=":", lw=1)
        a.text(p, 0.97 - 0.09 * n, f" {p:g} kg: healthy {h:,.0f} m³,\n failed {f:,.0f} m³ ({lost} lost) ",
               transform=a.get_xaxis_transform(), fontsize=8.5, va="top", ha="right" if p > 0.6 * top else "left",
               bbox=dict(fc="white", ec="none", alpha=0.85))
    a.set(xlabel="payload M [kg]", ylabel="volume of the voxels carrying M [m³]", xlim=(0, top * 1.02),
          title="How much: the volume that carries each payload")
    a.grid(alpha=0.3)
    a.legend(fontsize=8.5, loc="upper center", bbox_to_anchor=(0.5, -0.12))
    return "; ".join(verdicts)


def baseline_figure(df: pd.DataFrame, conv: pd.DataFrame, context: BaselineContext, out_png: str | Path) -> None:
    """What the failure cost, in two panels: how much (the volume carrying each payload M, healthy and
    failed on the arm's configuration and for any, the loss at the task payloads written) and where (the
    loss on the arm's configuration over the task start's voxel layer). The check of the angle step (the
    rise of the checked voxels' healthy values at half and a quarter of it) is a line under the title."""
    c = context
    fig, ax = plt.subplots(1, 2, figsize=(15, 7), layout="constrained")
    verdict = _volumes(ax[0], df, c.configuration, c.edge_m, c.payloads_kg)
    lo = grid_corner(df, c.edge_m)
    k = int(np.floor((c.start_m[2] - lo[2]) / c.edge_m))  # the task start's layer
    a = ax[1]
    img, extent = voxel_layer(df, "arm_configuration_loss_kg", k, c.edge_m)
    im = a.imshow(img, origin="lower", cmap="magma_r", extent=extent, interpolation="nearest",
                  vmin=min(0.0, float(np.nanmin(img, initial=0.0))))
    fig.colorbar(im, ax=a, label=f"loss on {c.configuration} [kg]: healthy − failed capacity (white: neither reaches)")
    lost = df[(df.k == k) & df.arm_configuration_capacity_kg.isna() & df.healthy_capacity_kg.notna()]
    a.plot(lost.x_m, lost.y_m, ".", color="tab:cyan", ms=5, label=f"{c.configuration} does not reach it: "
                                                                   "loss = the healthy value")
    neg = df[(df.k == k) & (df.arm_configuration_loss_kg < 0)]
    if len(neg):
        a.plot(neg.x_m, neg.y_m, "x", color="tab:green", ms=5, label="loss < 0 (the arms reach different points)")
    a.plot(c.start_m[0], c.start_m[1], "o", ms=11, mfc="white", mec="black", mew=1.5, label="task start")
    a.set(xlabel="x [m]", ylabel="y [m]", aspect="equal",
          title=f"Where: the loss over the task start's voxel layer, z = {lo[2] + (k + 0.5) * c.edge_m:.2f} m")
    a.legend(fontsize=8.5, loc="upper center", bbox_to_anchor=(0.5, -0.12))
    fig.suptitle(f"What the failure of joint {c.joint} (locked at {c.angle_deg:g} deg) cost: {verdict}\n"
                 + _convergence(conv, c), fontsize=11.5)
    save(fig, out_png)


def _convergence(conv: pd.DataFrame, c: BaselineContext) -> str:
    """The check of the angle search, in words: how far the checked voxels' healthy values lie below a
    sweep of the finer step (both are lower bounds of the healthy arm's)."""
    short = 100 * conv.shortfall_rel.dropna().to_numpy()
    if not len(short):
        return f"healthy values: best over a {c.step_deg:g} deg grid of the failed joint's angle, refined (no voxel checked)"
    return (f"healthy values are lower bounds; against a {c.check_step_deg:g} deg sweep, {len(short)} checked voxels lie "
            f"{max(short.max(), 0):.2g} % below at most ({int((short > 1).sum())} by more than 1 %)")
