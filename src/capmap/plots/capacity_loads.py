"""The loads of a verified task over time against their limits: joint torques, base force and base moment,
one panel per path, its verdict in its title."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import plt, save

__all__ = ["load_series", "load_label", "PATH_LABELS", "QUANTITY"]

PATH_LABELS = {"direct": "direct line", "planned": "planned path"}
QUANTITY = {"tau": ("joint torque", "N m"), "base_f": ("base disturbance force", "N"),
            "base_m": ("base disturbance moment", "N m")}


def load_label(column: str) -> str:
    """'tau_j3_nm' -> 'τ joint 3', 'base_fx_n' -> 'F_x', 'base_my_nm' -> 'M_y'."""
    if column.startswith("tau_j"):
        return f"τ joint {column.split('_')[1][1:]}"
    return f"{'F' if column.startswith('base_f') else 'M'}_{column.split('_')[1][1:]}"


def _peak(g: pd.DataFrame, columns: list[str], limits: dict) -> tuple[float, str, float]:
    """The tracked samples' largest |load| / limit over ``columns``: (ratio, column, time s)."""
    ok = g.tracked.to_numpy(bool) if "tracked" in g else np.ones(len(g), bool)
    best = (0.0, columns[0], 0.0)
    for c in columns:
        r = np.where(ok, np.abs(g[c].to_numpy(float)) / limits[c], np.nan)
        if np.isfinite(r).any() and np.nanmax(r) > best[0]:
            best = (float(np.nanmax(r)), c, float(g.t_s.to_numpy()[np.nanargmax(r)]))
    return best


def _also(g: pd.DataFrame, columns: list[str], limits: dict) -> tuple[list[str], str]:
    """The other loads of ``limits`` that the path exceeds (their names) and, in words, with their figures."""
    figs = {"tau": "torques.png", "base_f": "base_force.png", "base_m": "base_moment.png"}
    over = [k for k in limits if k not in columns and _peak(g, [k], limits)[0] > 1]
    groups = [(f, [load_label(k) for k in over if k.startswith(p)]) for p, f in figs.items()]
    return [load_label(k) for k in over], "; ".join(f"{', '.join(n)} ({f})" for f, n in groups if n)


def _spans(t: np.ndarray, over: np.ndarray) -> list[tuple[float, float]]:
    """The stretches (first, last time) where ``over`` holds."""
    edges = np.flatnonzero(np.diff(np.r_[0, over.astype(int), 0]))
    return [(float(t[a]), float(t[b - 1])) for a, b in zip(edges[::2], edges[1::2])]


def _mark_over(ax, t: np.ndarray, over: np.ndarray, top: float) -> None:
    """Shade where a load is over its limit; a stretch too short to see (under 2 % of the time axis) gets a
    red mark at the top and its times written, with an arrow."""
    if not over.any():
        return
    ax.fill_between(t, -top, top, where=over, color="tab:red", alpha=0.15, step="mid", lw=0, label="over its limit")
    span = float(np.ptp(t)) or 1.0
    for a, b in _spans(t, over):
        if b - a < 0.02 * span:
            ax.plot((a + b) / 2, 0.96 * top, "v", ms=11, color="tab:red", zorder=6)
            ax.annotate(f"over its limit: t = {a:.1f}-{b:.1f} s", xy=((a + b) / 2, 0.93 * top), xytext=(18, -58),
                        textcoords="offset points", ha="left", fontsize=9, color="tab:red", zorder=6,
                        bbox=dict(fc="white", ec="none", alpha=0.85, pad=1),
                        arrowprops=dict(arrowstyle="->", color="tab:red"))


def _mark_lost(ax, t: np.ndarray, t_lost: float, top: float) -> None:
    """Tracking lost at ``t_lost``: a black line and, grey to the line's planned end, the motion not executed."""
    ax.axvline(t_lost, color="black", lw=1.5)
    ax.axvspan(t_lost, t[-1], color="0.85", alpha=0.6, lw=0)
    ax.text(t_lost, -0.55 * top, f"  tracking lost at {t_lost:.1f} s: the rest of the\n  planned line "
            f"({t_lost:.1f}-{t[-1]:.1f} s, its planned end)\n  is not executed", fontsize=9, va="center")


def _panel(ax, g: pd.DataFrame, columns: list[str], limits: dict, name: str) -> str:
    """One path's loads against their limits, its verdict as the panel's title; returns its head line."""
    quantity, unit = next(v for k, v in QUANTITY.items() if columns[0].startswith(k))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    same = len({limits[k] for k in columns}) == 1
    t = g.t_s.to_numpy()
    lost = np.flatnonzero(~g.tracked.to_numpy(bool)) if "tracked" in g else np.array([], int)
    t_lost = t[lost[0]] if len(lost) else None
    over = np.zeros(len(g), bool)
    for n, col in enumerate(columns):
        c, y = colors[n % len(colors)], g[col].to_numpy(dtype=float)
        ax.plot(t, y, color=c, lw=1.2, label=load_label(col) + ("" if same else f" (limit ±{limits[col]:g} {unit})"))
        over |= np.abs(np.nan_to_num(y)) > limits[col]
    for n, col in enumerate(columns[:1] if same else columns):  # after the loads: the legend lists them first
        for sign in (1, -1):
            ax.axhline(sign * limits[col], color="0.3" if same else colors[n % len(colors)], ls=":", lw=1.4,
                       label=f"limit ±{limits[col]:g} {unit}" if same and sign > 0 else None)
    peak, at, t_peak = _peak(g, columns, limits)
    big = max((np.nanmax(np.abs(g[c])) for c in columns if np.isfinite(g[c]).any()), default=0.0)
    lim = max(limits[c] for c in columns)
    top = 1.3 * max(lim, big) if big <= 3 * lim else 2.5 * lim  # a spike beyond 3x the limit: off scale
    ax.set_ylim(-top, top)
    _mark_over(ax, t, over, top)
    if big > top:
        ax.annotate(f"off scale: {100 * peak:.0f} % of its limit at t = {t_peak:.1f} s", xy=(t_peak, 0.9 * top),
                    xytext=(10, 0), textcoords="offset points", fontsize=8.5, color="tab:red", va="center")
    if t_lost is not None:
        _mark_lost(ax, t, t_lost, top)
    label = PATH_LABELS.get(name, name)
    worst = f"{load_label(at)} at {100 * peak:.0f} % of its {limits[at]:g} {unit} limit (t = {t_peak:.1f} s)"
    verdict = (f"FAILS: tracking lost at {t_lost:.1f} s (singular); before it {worst}" if t_lost is not None
               else f"EXCEEDS a limit: {worst}" if peak > 1 else f"within limits: peak {worst}")
    ok = peak <= 1 and t_lost is None
    names, also = _also(g, columns, limits)
    ax.set(ylabel=f"{quantity} [{unit}]")
    ax.set_title(f"{label} {verdict}" + (f"\n{'but' if ok else 'it also'} exceeds {also}" if also else ""),
                 fontsize=10.5, color="black" if ok else "tab:red")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    return (f"{label} {'within limits' if ok else 'FAILS'} ({100 * peak:.0f} %)"
            + (f" but fails on {', '.join(names)}" if ok and names else ""))


def load_series(ts: pd.DataFrame, columns: list[str], limits: dict, title: str, out_png: str | Path) -> None:
    """One panel per path: the given loads over time against their ±limits (dotted: one grey pair when all
    share one limit, else in the colour of its load), the verdict in the panel's and the figure's title (the
    peak as % of its limit, the load that reaches it; the other limits of ``limits`` a path exceeds named),
    what breaks a limit shaded red (a stretch too short to see also barred and its times written), the time
    tracking was lost marked (the rest of the planned motion, to its planned end, not executed), a spike far
    above the limits drawn off scale with its peak written; legends beside the panels, off the curves."""
    paths = list(ts.path.cat.categories if hasattr(ts.path, "cat") else ts.path.unique())
    fig, axes = plt.subplots(len(paths), 1, figsize=(12.5, 3.4 * len(paths) + 0.8), squeeze=False, sharex=True,
                             layout="constrained")
    heads = [_panel(ax, ts[ts.path == name], columns, limits, name) for ax, name in zip(axes[:, 0], paths)]
    axes[-1, 0].set_xlabel("time t [s]")
    fig.suptitle(f"{title}: " + "; ".join(heads) + ("" if "planned" in paths else " (no planned path at this payload)"),
                 fontsize=12)
    save(fig, out_png)
