"""The loads of a verified task over time against their limits: joint torques, base force and base moment,
one panel per path (its verdict in one line), one legend for both; the load that binds a path's capacity marked."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from capmap.plots.common import plt, save

__all__ = ["load_series", "load_label", "PATH_LABELS", "QUANTITY", "MINOR"]

PATH_LABELS = {"direct": "direct line", "planned": "planned path"}
QUANTITY = {"tau": ("joint torque", "N m"), "base_f": ("base disturbance force", "N"),
            "base_m": ("base disturbance moment", "N m")}
MINOR = 0.15  # a load whose peak stays under this share of its limit on every path: grey, one legend entry


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


def _also(g: pd.DataFrame, columns: list[str], limits: dict) -> list[str]:
    """The other loads of ``limits`` that the path exceeds (their names)."""
    return [load_label(k) for k in limits if k not in columns and _peak(g, [k], limits)[0] > 1]


def _names(columns: list[str]) -> str:
    """'τ joints 5, 6, 7' for torques, else 'F_x, F_z'."""
    if len(columns) > 1 and all(c.startswith("tau_j") for c in columns):
        return "τ joints " + ", ".join(c.split("_")[1][1:] for c in columns)
    return ", ".join(load_label(c) for c in columns)


def _binding(g: pd.DataFrame, limits: dict) -> str:
    """The load that binds a path's capacity: the one binding its weakest tracked state ('' when not known)."""
    if "binding" not in g or "state_capacity_kg" not in g:
        return ""
    ok = g.tracked.to_numpy(bool) if "tracked" in g else np.ones(len(g), bool)
    cap = np.where(ok, g.state_capacity_kg.to_numpy(float), np.nan)
    b = str(g.binding.iloc[int(np.nanargmin(cap))]) if np.isfinite(cap).any() else ""
    return b if b in limits else ""


def _minor(ts: pd.DataFrame, columns: list[str], limits: dict) -> tuple[list[str], float]:
    """The loads whose peak stays under :data:`MINOR` of their limit on every path (drawn grey, one legend entry;
    only when there are two or more and others) and their largest peak as a share of the limit."""
    ok = ts.tracked.to_numpy(bool) if "tracked" in ts else np.ones(len(ts), bool)
    share = {c: float(np.nanmax(np.abs(ts[c].to_numpy(float)[ok]), initial=0.0)) / limits[c] for c in columns}
    small = [c for c in columns if share[c] < MINOR]
    if len(small) < 2 or len(small) == len(columns):
        return [], 0.0
    return small, max(share[c] for c in small)


def _spans(t: np.ndarray, over: np.ndarray) -> list[tuple[float, float]]:
    """The stretches (first, last time) where ``over`` holds."""
    edges = np.flatnonzero(np.diff(np.r_[0, over.astype(int), 0]))
    return [(float(t[a]), float(t[b - 1])) for a, b in zip(edges[::2], edges[1::2])]


def _mark_over(ax, t: np.ndarray, over: np.ndarray, lim: float, top: float) -> None:
    """Shade where a load is over its limit, each stretch at least 1.5 % of the time axis wide; a stretch too
    short to read (under 2 %) gets its times written beside it, between the limit line and the edge."""
    span = float(np.ptp(t)) or 1.0
    for a, b in _spans(t, over):
        w, c = max(b - a, 0.015 * span), (a + b) / 2
        ax.axvspan(c - w / 2, c + w / 2, color="tab:red", alpha=0.25, lw=0, zorder=1.5)
        if b - a < 0.02 * span:
            ax.annotate(f"over its limit: t = {a:.1f}-{b:.1f} s", xy=(c + w / 2, (lim + top) / 2), xytext=(4, 0),
                        textcoords="offset points", ha="left", va="center", fontsize=9, color="tab:red", zorder=6,
                        bbox=dict(fc="white", ec="none", alpha=0.85, pad=1))


def _mark_off(ax, g: pd.DataFrame, columns: list[str], limits: dict, top: float) -> None:
    """A load that leaves the plot: a red arrowhead on the edge it leaves by, where it first does, the loads that
    leave there and how far they go (as a share of the limit, signed)."""
    t = g.t_s.to_numpy()
    for sign in (1, -1):
        cols = [c for c in columns if np.nanmax(sign * g[c].to_numpy(float), initial=-np.inf) > top]
        if not cols:
            continue
        first = min(t[np.argmax(sign * g[c].to_numpy(float) > top)] for c in cols)
        far = max(np.nanmax(sign * g[c].to_numpy(float)) / limits[c] for c in cols)
        ax.plot(first, sign * 0.965 * top, "^" if sign > 0 else "v", ms=11, color="tab:red", zorder=6)
        ax.annotate(f"{_names(cols)}: off scale, {'up' if sign > 0 else 'down'} to {sign * 100 * far:+.0f} % of the "
                    "limit", (first, sign * 0.965 * top), xytext=(12, -9 * sign), textcoords="offset points", va="center",
                    fontsize=9, color="tab:red", zorder=6, bbox=dict(fc="white", ec="none", alpha=0.85, pad=1))


def _mark_lost(ax, t: np.ndarray, t_lost: float, top: float) -> None:
    """Tracking lost at ``t_lost``: a black line and, grey to the line's planned end, the motion not executed."""
    ax.axvline(t_lost, color="black", lw=1.5)
    ax.axvspan(t_lost, t[-1], color="0.85", alpha=0.6, lw=0)
    ax.text(t_lost, -0.5 * top, f"  tracking lost at {t_lost:.1f} s: the rest ({t_lost:.1f}-{t[-1]:.1f} s) not "
            "executed", fontsize=9, va="center")


def _panel(ax, g: pd.DataFrame, columns: list[str], limits: dict, name: str, minor: list[str], binds: str) -> str:
    """One path's loads against their limits (``minor`` loads grey, the load that ``binds`` its capacity thick,
    its weakest state marked on it), its verdict as the panel's one-line title; returns its head line."""
    quantity, unit = next(v for k, v in QUANTITY.items() if columns[0].startswith(k))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    t = g.t_s.to_numpy()
    lost = np.flatnonzero(~g.tracked.to_numpy(bool)) if "tracked" in g else np.array([], int)
    t_lost = t[lost[0]] if len(lost) else None
    over = np.zeros(len(g), bool)
    for n, col in enumerate(columns):
        y = g[col].to_numpy(dtype=float)
        ax.plot(t, y, **(dict(color="0.6", lw=1.0, zorder=1.8) if col in minor else
                         dict(color=colors[n % len(colors)], lw=2.6 if col == binds else 1.2)))
        over |= np.abs(np.nan_to_num(y)) > limits[col]
    same = len({limits[k] for k in columns}) == 1
    for n, col in enumerate(columns[:1] if same else columns):
        for sign in (1, -1):
            ax.axhline(sign * limits[col], color="0.3" if same else colors[n % len(colors)], ls=":", lw=1.4)
    peak, at, t_peak = _peak(g, columns, limits)
    big = max((np.nanmax(np.abs(g[c])) for c in columns if np.isfinite(g[c]).any()), default=0.0)
    lim = max(limits[c] for c in columns)
    top = 1.3 * max(lim, big) if big <= 3 * lim else 2.5 * lim  # a spike beyond 3x the limit: off scale
    ax.set_ylim(-top, top)
    _mark_over(ax, t, over, lim, top)
    _mark_off(ax, g, columns, limits, top)
    if binds in columns and t_lost is None:  # a path that lost tracking: its weakest state is the singular one (0 kg)
        k = int(np.nanargmin(np.where(g.tracked.to_numpy(bool) if "tracked" in g else True,
                                      g.state_capacity_kg.to_numpy(float), np.nan)))
        ax.plot(t[k], g[binds].to_numpy(float)[k], "X", ms=11, mfc="white", mec="black", zorder=7)
    if t_lost is not None:
        _mark_lost(ax, t, t_lost, top)
    label = PATH_LABELS.get(name, name)
    worst = f"{load_label(at)} at {100 * peak:.0f} % of its {limits[at]:g} {unit} limit (t = {t_peak:.1f} s)"
    verdict = (f"FAILS: tracking lost at {t_lost:.1f} s (singular); before it {worst}" if t_lost is not None
               else f"EXCEEDS a limit: {worst}" if peak > 1 else f"within limits: peak {worst}")
    ok = peak <= 1 and t_lost is None
    ax.set(ylabel=f"{quantity} [{unit}]")
    ax.set_title(f"{label} {verdict}", fontsize=10.5, color="black" if ok else "tab:red")
    ax.grid(alpha=0.3)
    names = _also(g, columns, limits)
    if t_lost is not None:
        return f"{label} FAILS: singular at t = {t_lost:.1f} s"
    return (f"{label} {'within limits' if ok else 'FAILS'} ({100 * peak:.0f} %)"
            + (f" but fails on {', '.join(names)}" if ok and names else ""))


def _legend(fig, ts: pd.DataFrame, columns: list[str], limits: dict, minor: tuple, binds: set[str]) -> None:
    """One legend for the panels, beside them: each load (the one that binds marked), the minor loads as one
    entry, the limit, and the marks the panels use."""
    quantity, unit = next(v for k, v in QUANTITY.items() if columns[0].startswith(k))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    same = len({limits[k] for k in columns}) == 1
    handles = [Line2D([], [], color=colors[n % len(colors)], lw=2.6 if c in binds else 1.2,
                      label=load_label(c) + (" (binds)" if c in binds else "")
                      + ("" if same else f" (limit ±{limits[c]:g} {unit})"))
               for n, c in enumerate(columns) if c not in minor[0]]
    if minor[0]:
        handles.append(Line2D([], [], color="0.6", lw=1.0, label=f"{_names(minor[0])}: under {100 * minor[1]:.0f} % "
                                                                  "of the limit"))
    if same:
        handles.append(Line2D([], [], color="0.3", ls=":", lw=1.4, label=f"limit ±{limits[columns[0]]:g} {unit}"))
    if any(_peak(ts[ts.path == p], [c], limits)[0] > 1 for p in ts.path.unique() for c in columns):
        handles.append(Patch(color="tab:red", alpha=0.25, lw=0, label="over its limit"))
    if binds & set(columns):
        handles.append(Line2D([], [], ls="none", marker="X", ms=9, mfc="white", mec="black",
                              label="weakest state (binds)"))
    if "tracked" in ts and not ts.tracked.all():
        handles.append(Line2D([], [], color="black", lw=1.5, label="tracking lost"))
    fig.legend(handles=handles, loc="outside right center", fontsize=9, frameon=False)


def load_series(ts: pd.DataFrame, columns: list[str], limits: dict, title: str, out_png: str | Path) -> None:
    """One panel per path: the given loads over time against their ±limits (dotted: one grey pair when all
    share one limit, else in the colour of its load), the verdict in one line in the panel's title and the
    figure's (the peak as % of its limit, the load that reaches it; in the headline, the other limits of
    ``limits`` a path exceeds and the load that binds its capacity, at its weakest state: that load drawn
    thick and its weakest state marked where this figure shows it); loads far under their limits on every path
    grey, one legend entry; what breaks a limit shaded red (at least a visible width; a short stretch's times
    written), the time tracking was lost marked (the rest of the planned motion, to its planned end, not
    executed), a spike far beyond the limits drawn off scale with an arrowhead on the edge it leaves by; one
    legend beside the panels."""
    paths = list(ts.path.cat.categories if hasattr(ts.path, "cat") else ts.path.unique())
    minor = _minor(ts, columns, limits)
    binds = {name: _binding(ts[ts.path == name], limits) for name in paths}
    fig, axes = plt.subplots(len(paths), 1, figsize=(12.5, 3.3 * len(paths) + 0.6), squeeze=False, sharex=True,
                             layout="constrained")
    heads = [_panel(ax, ts[ts.path == name], columns, limits, name, minor[0], binds[name])
             for ax, name in zip(axes[:, 0], paths)]
    axes[-1, 0].set_xlabel("time t [s]")
    _legend(fig, ts, columns, limits, minor, {b for b in binds.values() if b})
    bound = list(dict.fromkeys(b for b in binds.values() if b))
    fig.suptitle(f"{title}: " + "; ".join(heads) + ("" if "planned" in paths else " (no planned path)")
                 + (f"; capacity bound by {', '.join(('base ' if b.startswith('base') else '') + load_label(b) for b in bound)}"
                    if bound else ""), fontsize=12)
    save(fig, out_png)
