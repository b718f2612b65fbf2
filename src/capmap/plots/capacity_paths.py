"""One verified task's workspace: does each path carry its payload, and where is it weak? Left, the map of the
arm's configuration on the plane of the paths coloured by capacity (each voxel's least over its points and every
direction), each path drawn in its colour around a core coloured by its own capacity (each segment's, verified
along its own direction on its own IK branch, on the same scale), so that a path holding across weaker voxels
shows it; right, each path's own capacity state by state against the voxels under it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import patheffects
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from capmap.plots.capacity_cuts import (
    CASING,
    CMAP,
    ZERO_LABEL,
    cased_path,
    hatch_zero,
    mark_ends,
    plane_cut,
    unreached_handle,
    volume,
)
from capmap.plots.common import plt, save

__all__ = ["workspace_paths", "PATH_STYLE"]

PATH_STYLE = {"direct": {"color": "black", "label": "direct line"},
              "planned": {"color": "darkorange", "label": "planned path"}}
HATCH = "0.8"  # the 0 kg cells' hatch: light, to read on the dark end of viridis


def _path_table(ts: pd.DataFrame, payload_kg: float) -> dict:
    """Per path: its samples ``g``, each state's capacity ``cap`` (NaN where not tracked; inf: cruising, the
    payload adds no load), the weakest (kg, its row ``k``), where tracking was lost (row; None), the states
    below ``payload_kg``, whether it stays in its joint range and carries the payload."""
    out = {}
    for name, g in ts.groupby("path", observed=True, sort=False):
        g = g.reset_index(drop=True)
        ok = g.tracked.to_numpy(bool) if "tracked" in g else np.ones(len(g), bool)
        cap = np.where(ok, g.state_capacity_kg.to_numpy(float), np.nan)
        k = int(np.nanargmin(cap)) if np.isfinite(cap).any() else 0
        p = dict(g=g, cap=cap, weakest=float(cap[k]) if np.isfinite(cap).any() else 0.0, k=k,
                 lost=None if ok.all() else int(np.flatnonzero(~ok)[0]), below=ok & (cap < payload_kg),
                 in_range=bool(g.in_joint_range.all()) if "in_joint_range" in g else True)
        out[name] = {**p, "holds": p["weakest"] >= payload_kg and p["lost"] is None and p["in_range"]}
    return out


def _verdict(name: str, p: dict, payload_kg: float) -> str:
    """A path's panel title, one line: e.g. 'planned path holds: weakest segment 4,149 kg (+3.7 %)'; where a
    path holds across voxels below its payload, how low they go; where tracking was lost."""
    label = PATH_STYLE.get(name, {}).get("label", name)
    g, s = p["g"], p["g"].distance_m.to_numpy()
    if p["lost"] is not None:
        return (f"{label} FAILS: tracking lost at {s[p['lost']]:.2f} m (t = {g.t_s.iloc[p['lost']]:.1f} s), "
                "a singular surface")
    vox = g.voxel_kg.to_numpy(float)
    under = (f"; voxels under it down to {np.nanmin(vox):,.0f} kg" if p["holds"] and (vox < payload_kg).any() else "")
    return (f"{label} {'holds' if p['holds'] else 'FAILS'}: weakest segment {p['weakest']:,.0f} kg "
            f"({100 * (p['weakest'] / payload_kg - 1):+.1f} %)" + ("" if p["in_range"] else ", leaves its joint range")
            + under)


def _story(paths: dict, payload_kg: float, no_path: str) -> str:
    """The headline after the payload, one line: what the two paths say together, from their verdicts."""
    d, q = paths.get("direct"), paths.get("planned")
    if q is None:
        return f"no planned path ({no_path}); the direct line {'holds' if d and d['holds'] else 'fails'}"
    if d is None:
        return f"the planned path {'holds' if q['holds'] else 'FAILS'} ({q['weakest']:,.0f} kg)"
    if d["holds"] and q["holds"]:
        dt, qt = d["g"].t_s.iloc[-1], q["g"].t_s.iloc[-1]
        if d["weakest"] >= q["weakest"] and dt <= qt:
            return (f"both paths hold; the direct line has more margin ({d['weakest']:,.0f} vs {q['weakest']:,.0f} kg) "
                    f"and is faster ({dt:.0f} vs {qt:.0f} s)")
        return f"both paths hold (direct line {d['weakest']:,.0f} kg, planned path {q['weakest']:,.0f} kg)"
    why = ("tracking lost at a singular surface" if d["lost"] is not None
           else f"{d['weakest']:,.0f} kg < {payload_kg:g} kg" if not d["holds"] else "")
    return (f"the direct line {'fails (' + why + ')' if not d['holds'] else 'holds'}, the planned path "
            f"{'holds' if q['holds'] else 'FAILS'} ({q['weakest']:,.0f} kg)")


def _draw_path(ax, project, p: dict, norm, style: dict, payload_kg: float) -> Line2D:
    """One path on the plane: a red halo where a state is below the payload, its colour around its segments'
    capacity (:func:`cased_path`), thin and faded where not executed (tracking lost), its weakest state marked
    (X, red when below the payload) with its capacity. Returns its legend handle."""
    h, v, _ = project(p["g"][["x_m", "y_m", "z_m"]].to_numpy())
    n = len(h) if p["lost"] is None else p["lost"]
    if p["below"][:n].any():
        ax.plot(h[:n], np.where(p["below"][:n], v[:n], np.nan), color="tab:red", lw=CASING + 5, alpha=0.85,
                zorder=9.5, solid_capstyle="butt")
    seg = p["g"].segment_capacity_kg.to_numpy(float) if "segment_capacity_kg" in p["g"] else p["cap"]
    handle = cased_path(ax, h[:n], v[:n], seg[1:n], norm, style["color"], style.get("label"))
    if n < len(h):
        ax.plot(h[n - 1:], v[n - 1:], color=style["color"], lw=1.5, ls=":", zorder=9.8)
    k = p["k"]
    ax.plot(h[k], v[k], "X", ms=12, mfc="white" if p["holds"] else "tab:red", mec="black", zorder=13)
    ax.annotate(f"{p['weakest']:,.0f} kg", (h[k], v[k]), xytext=(10, -22), textcoords="offset points", fontsize=9,
                bbox=dict(fc="white", ec="none", alpha=0.85, pad=1), zorder=13,
                arrowprops=dict(arrowstyle="-", color="0.3", lw=0.8))
    return handle


def _plane(ax, main: pd.DataFrame, ts: pd.DataFrame, paths: dict, payload_kg: float, colour: str):
    """Left: the map's voxels on the plane of the paths (the horizontal layer when they stay in one) coloured by
    capacity, 0 kg hatched, the payload's contour (white), the paths (:func:`_draw_path`), start and goal.
    Returns the image (its norm: the map's capacity scale) and the legend handles."""
    grid = main.attrs["capmap"]["grid"]
    start, goal = next(iter(paths.values()))["g"][["x_m", "y_m", "z_m"]].to_numpy()[[0, -1]]
    flat = start[2] if np.ptp(ts.z_m.to_numpy()) <= grid["edge_m"] / 2 else None
    cap = main.capacity_kg.to_numpy()
    norm = Normalize(0.0, float(np.nanmax(np.r_[cap[main.n_reachable > 0], 1.0])))
    img, extent, project = plane_cut(volume(main, cap), grid, start, goal, flat)
    im = ax.imshow(img, origin="lower", extent=extent, interpolation="nearest", cmap=CMAP, norm=norm)
    hatch_zero(ax, img == 0, extent, HATCH, label=False)
    handles = [Patch(fc="0.35", ec=HATCH, hatch="xxx", label=ZERO_LABEL), unreached_handle()]
    if np.nanmin(img, initial=np.inf) < payload_kg <= np.nanmax(img, initial=-np.inf):
        ax.contour(np.where(np.isnan(img), -1.0, img), levels=[payload_kg], colors="white", linewidths=1.8,
                   extent=extent, origin="lower")
        handles.append(Line2D([], [], color="white", lw=1.8, label=f"white line: {payload_kg:g} kg in every direction",
                              path_effects=[patheffects.Stroke(linewidth=3.6, foreground="0.35"), patheffects.Normal()]))
    lines = [_draw_path(ax, project, p, norm, {**PATH_STYLE.get(name, {"label": name, "color": "0.3"}),
                                               **({"color": colour} if name == "planned" else {})}, payload_kg)
             for name, p in paths.items()]
    lines.append(Line2D([], [], ls="none", marker="X", ms=9, mfc="white", mec="black", label="weakest state"))
    if any(p["below"].any() for p in paths.values()):
        lines.append(Line2D([], [], color="tab:red", lw=6, alpha=0.85, label=f"below {payload_kg:g} kg"))
    if any(p["lost"] is not None for p in paths.values()):
        lines.append(Line2D([], [], color="black", lw=1.5, ls=":", label="not executed (tracking lost)"))
    mark_ends(ax, project, start, goal)
    h, v, _ = project(ts[["x_m", "y_m", "z_m"]].to_numpy())
    pad = 2.5 * grid["edge_m"]
    ax.set(xlim=(h.min() - pad, h.max() + pad), ylim=(v.min() - pad, v.max() + pad), aspect="equal",
           xlabel="x [m]" if flat is not None else "horizontal distance from the start towards the goal [m]",
           ylabel="y [m]" if flat is not None else "height z [m]")
    ax.set_title(f"voxel layer z = {flat:.2f} m" if flat is not None else "vertical plane through start and goal",
                 fontsize=11)
    return im, lines + handles


def _profile(ax, name: str, p: dict, payload_kg: float, colour: str) -> None:
    """One path's own capacity, state by state, against distance travelled (gaps: cruising, unbounded); the
    voxels' value under it and the payload; red where it is below; a black line where tracking was lost."""
    g = p["g"]
    n = len(g) if p["lost"] is None else p["lost"]
    s, cap, vox = g.distance_m.to_numpy()[:n], p["cap"][:n], g.voxel_kg.to_numpy(float)[:n]
    top = float(np.nanmax(np.r_[cap[np.isfinite(cap)], vox[np.isfinite(vox)], payload_kg]))
    ax.plot(s, vox, color="0.55", lw=1.2)
    ax.plot(s, np.where(np.isfinite(cap), cap, np.nan), color=colour, lw=3, zorder=5)
    ax.axhline(payload_kg, color="tab:red", lw=1.5)
    ax.fill_between(s, 0, 1, where=p["below"][:n], color="tab:red", alpha=0.15, transform=ax.get_xaxis_transform(),
                    lw=0, step="mid")
    if p["lost"] is not None:
        at = g.distance_m.iloc[p["lost"]]
        ax.axvline(at, color="black", lw=1.5)
        ax.annotate("tracking lost", (at, 0.55), xycoords=ax.get_xaxis_transform(), xytext=(5, 0),
                    textcoords="offset points", fontsize=9.5, va="center")
    k = p["k"]
    ax.plot(s[k], cap[k], "X", ms=11, mfc="white" if cap[k] >= payload_kg else "tab:red", mec="black", zorder=7,
            clip_on=False)
    right = s[k] > 0.75 * np.nanmax(g.distance_m)  # its label on the side with room
    ax.annotate(f"{cap[k]:,.0f} kg", (s[k], cap[k]), xytext=(-8 if right else 8, 6), textcoords="offset points",
                fontsize=9, ha="right" if right else "left", bbox=dict(fc="white", ec="none", alpha=0.85, pad=1),
                zorder=7)
    ax.set(ylim=(-0.04 * top, 1.12 * top), ylabel="capacity [kg]")
    ax.set_title(_verdict(name, p, payload_kg), fontsize=10.5, color="black" if p["holds"] else "tab:red")
    ax.grid(alpha=0.3)


def workspace_paths(main: pd.DataFrame, ts: pd.DataFrame, payload_kg: float, out_png: str | Path, which: str,
                    no_path: str = "", colour: str = PATH_STYLE["planned"]["color"]) -> None:
    """Does each path carry ``payload_kg``, and where is it weak? Left: the voxels of ``main`` (the map of the
    arm's configuration, named ``which``) on the vertical plane through start and goal (the horizontal layer
    when the paths stay in one), coloured by capacity, 0 kg hatched, the payload's contour; each path in its
    colour (the direct line black, the planned path ``colour``) around a core coloured by its segments'
    capacity (``ts`` column ``segment_capacity_kg``), red around where a state is below the payload, its weakest
    state marked. Right, one panel per path: its own capacity state by state (``state_capacity_kg``: along its
    direction at its timed motion; cruising it is unbounded: a gap) against ``distance_m`` travelled, the map's
    value of the voxel under it (``voxel_kg``) and the payload. The headline: both verdicts in one line;
    ``no_path``: why there is no planned path ('' when there is one)."""
    paths = _path_table(ts, payload_kg)
    fig = plt.figure(figsize=(16, 8.4), layout="constrained")
    sub = fig.subfigures(1, 2, width_ratios=[1.1, 1])
    ax, axes = sub[0].subplots(), sub[1].subplots(len(paths), 1, sharex=True, squeeze=False)[:, 0]
    im, handles = _plane(ax, main, ts, paths, payload_kg, colour)
    seg = np.concatenate([p["g"].segment_capacity_kg.to_numpy(float) for p in paths.values()]) \
        if "segment_capacity_kg" in ts else np.zeros(1)
    cb = sub[0].colorbar(im, ax=ax, shrink=0.85, label="capacity [kg]",
                         extend="max" if np.nanmax(seg, initial=0.0) > im.norm.vmax else "neither")
    if payload_kg <= im.norm.vmax:
        cb.ax.axhline(payload_kg, color="white", lw=2)
    sub[0].legend(handles=handles, loc="outside lower center", ncol=3, fontsize=9)
    for a, (name, p) in zip(axes, paths.items()):
        _profile(a, name, p, payload_kg, colour if name == "planned" else PATH_STYLE.get(name, {}).get("color", "0.3"))
    axes[-1].set_xlabel("distance travelled along the path [m]")
    cruise = any(np.isinf(p["cap"]).any() for p in paths.values())
    sub[1].legend(handles=[Line2D([], [], color="0.3", lw=3, label="the path's own capacity (verified)"),
                           Line2D([], [], color="0.55", lw=1.2, label="voxel under it (map)"),
                           Line2D([], [], color="tab:red", lw=1.5, label=f"payload {payload_kg:g} kg")]
                  + [Line2D([], [], color="none", label="gaps: cruising, no limit")] * cruise,
                  loc="outside lower center", ncol=2, fontsize=9)
    fig.suptitle(f"Carrying {payload_kg:g} kg on {which}: {_story(paths, payload_kg, no_path)}", fontsize=12.5,
                 color="black" if any(p["holds"] for p in paths.values()) else "tab:red")
    save(fig, out_png)
