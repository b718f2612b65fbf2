"""One verified task's workspace: does each path carry its payload, where along it does it fail, and why may a
path cross voxels the map says carry less (the map: the least over the whole voxel and every direction; a path:
each state of its own timed motion, along its own direction, on its own IK branch)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.colors import BoundaryNorm, ListedColormap

from capmap.plots.capacity_cuts import hatch_zero, mark_ends, plane_cut, volume
from capmap.plots.capacity_loads import load_label
from capmap.plots.common import plt, save

__all__ = ["workspace_paths", "PATH_STYLE", "CLASSES"]

PATH_STYLE = {"direct": {"color": "black", "ls": "--", "label": "direct line"},
              "planned": {"color": "tab:blue", "ls": "-", "label": "planned path"}}
# the workspace figure's voxel classes for a payload M (least over every direction; best of the 13 grid axes)
CLASSES = (("carries M in every direction", "#1b7837"), ("carries M along some grid axes only", "#a6dba0"),
           ("carries M along no grid axis", "#d9d9d9"))
VERBS = {"accelerate": "accelerates", "cruise": "cruises", "decelerate": "decelerates"}


def _spans(s: np.ndarray, where: np.ndarray) -> list[tuple[float, float]]:
    """The stretches (first, last distance) where ``where`` holds."""
    edges = np.flatnonzero(np.diff(np.r_[0, where.astype(int), 0]))
    return [(float(s[a]), float(s[b - 1])) for a, b in zip(edges[::2], edges[1::2])]


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


def _where_weak(p: dict, payload_kg: float) -> str:
    """Where a path is weak, in words: the stretches below the payload and in which phases, else where its
    weakest state is (the phase, the move, the load that binds)."""
    g, s = p["g"], p["g"].distance_m.to_numpy()
    phase = g.phase.astype(str).to_numpy() if "phase" in g else np.full(len(g), "")
    b = str(g.binding.iloc[p["k"]]) if "binding" in g else ""
    bind = f" ({'base ' if b.startswith('base') else ''}{load_label(b)} binds)" if b[:3] in ("tau", "bas") else ""
    if p["below"].any():
        verbs = [VERBS.get(v, v) for v in dict.fromkeys(phase[p["below"]]) if v]
        spans = ", ".join(f"{a:.2f}-{b:.2f} m" for a, b in _spans(s, p["below"]))
        return f"below {payload_kg:g} kg while it {' and '.join(verbs) or 'moves'} ({spans}){bind}"
    n = int(g.segment.max()) + 1 if "segment" in g else 1
    move = f" on move {int(g.segment.iloc[p['k']]) + 1} of {n}" if n > 1 else ""
    return f"weakest while it {VERBS.get(phase[p['k']], 'moves')}{move}{bind}"


def _verdict(name: str, p: dict, payload_kg: float) -> str:
    """The panel's title: the verdict (e.g. 'planned path holds: weakest segment 4149 kg (+3.7 % margin)') and,
    on a second line, where it is weak or where it was lost."""
    label = PATH_STYLE.get(name, {}).get("label", name)
    g, s = p["g"], p["g"].distance_m.to_numpy()
    if p["lost"] is not None:
        zero = np.flatnonzero(p["cap"] == 0)
        return (f"{label} FAILS: tracking lost at {s[p['lost']]:.2f} m (t = {g.t_s.iloc[p['lost']]:.1f} s): "
                "a singular surface" + (f"\n0 kg from {s[zero[0]]:.2f} m: near it the arm's own motion alone exceeds "
                                        "a limit" if len(zero) else ""))
    return (f"{label} {'holds' if p['holds'] else 'FAILS'}: weakest segment {p['weakest']:.0f} kg "
            f"({100 * (p['weakest'] / payload_kg - 1):+.1f} % margin)" + ("" if p["in_range"] else
                                                                       ", but it leaves its joint range") +
            "\n" + _where_weak(p, payload_kg))


def _story(paths: dict, payload_kg: float, planner: str, no_path: str) -> str:
    """The figure's title after the payload: what the two paths say together, from their verdicts; what the
    planner looks for when the paths are compared."""
    d, q = paths.get("direct"), paths.get("planned")
    if q is None:
        return f"no planned path ({no_path}); direct line {'holds' if d and d['holds'] else 'fails'}"
    plan = f"\nthe planned path is what A* finds: {planner}" if planner else ""
    if d is None:
        return f"planned path {'holds' if q['holds'] else 'fails'}{plan}"
    if d["holds"] and q["holds"]:
        dt, qt = d["g"].t_s.iloc[-1], q["g"].t_s.iloc[-1]
        if d["weakest"] >= q["weakest"] and dt <= qt:
            return (f"both paths hold, and the direct line is the better motion here\n(weakest segment "
                    f"{d['weakest']:,.0f} vs {q['weakest']:,.0f} kg, {dt:.0f} vs {qt:.0f} s): at this payload the plan "
                    "is not needed" + plan + ",\nat rest at each waypoint: it does not seek the largest margin")
        return "both paths hold" + plan
    why = ("tracking lost at a singular surface" if d["lost"] is not None
           else f"{d['weakest']:,.0f} kg < {payload_kg:g} kg" if not d["holds"] else "")
    return (f"direct line {'fails (' + why + ')' if not d['holds'] else 'holds'}, planned path "
            f"{'holds' if q['holds'] else 'FAILS'} ({q['weakest']:,.0f} kg)" + plan)


def _plane(ax, main: pd.DataFrame, ts: pd.DataFrame, paths: dict, payload_kg: float, which: str) -> None:
    """Left: the map's voxels on the plane of the paths in three classes for the payload, 0 kg hatched, the
    paths (red where a state is below the payload, faded where not executed) and their weakest states."""
    grid = main.attrs["capmap"]["grid"]
    start, goal = next(iter(paths.values()))["g"][["x_m", "y_m", "z_m"]].to_numpy()[[0, -1]]
    cls = np.select([main.capacity_kg >= payload_kg, main.capacity_best_axis_kg >= payload_kg], [0.0, 1.0], 2.0)
    flat = start[2] if np.ptp(ts.z_m.to_numpy()) <= grid["edge_m"] / 2 else None
    img, extent, project = plane_cut(volume(main, cls), grid, start, goal, flat)
    ax.imshow(img, origin="lower", extent=extent, interpolation="nearest", cmap=ListedColormap([c for _, c in CLASSES]),
              norm=BoundaryNorm([-0.5, 0.5, 1.5, 2.5], 3))
    for label, colour in CLASSES + (("not reached on this configuration", "white"),):
        ax.fill([], [], fc=colour, ec="0.5", label=label.replace("M", f"{payload_kg:g} kg"))
    hatch_zero(ax, plane_cut(volume(main, main.capacity_kg.to_numpy() == 0), grid, start, goal, flat)[0] == 1, extent)
    off, faded = 0.0, False
    for name, p in paths.items():
        h, v, o = project(p["g"][["x_m", "y_m", "z_m"]].to_numpy())
        off = max(off, float(o.max()))
        style = PATH_STYLE.get(name, {"label": name})
        n = len(h) if p["lost"] is None else p["lost"]
        ax.plot(h[:n], v[:n], lw=3, zorder=10, **style)
        if n < len(h):
            faded = True
            ax.plot(h[n - 1:], v[n - 1:], lw=1.5, zorder=10, alpha=0.35, **{**style, "label": None})
        red = np.where(p["below"], v, np.nan)
        ax.plot(h, red, color="tab:red", lw=5, alpha=0.8, zorder=11, solid_capstyle="butt")
        ax.plot(h[p["k"]], v[p["k"]], "X", ms=12, mfc="white" if p["holds"] else "tab:red", mec="black", zorder=13)
        ax.annotate(f"{p['weakest']:.0f} kg", (h[p["k"]], v[p["k"]]), xytext=(10, -22), textcoords="offset points",
                    fontsize=9, bbox=dict(fc="white", ec="none", alpha=0.85, pad=1), zorder=13,
                    arrowprops=dict(arrowstyle="-", color="0.3", lw=0.8))
    ax.plot([], [], "X", ms=9, mfc="white", mec="black", label="weakest state of each path (red: below the payload)")
    if any(p["below"].any() for p in paths.values()):
        ax.plot([], [], color="tab:red", lw=6, alpha=0.75, label=f"states below {payload_kg:g} kg")
    if faded:
        ax.plot([], [], color="black", lw=1.5, alpha=0.35, label="not executed: tracking lost")
    mark_ends(ax, project, start, goal)
    h, v, _ = project(ts[["x_m", "y_m", "z_m"]].to_numpy())
    pad = 3 * grid["edge_m"]
    ax.set(xlim=(h.min() - pad, h.max() + pad), ylim=(v.min() - pad, v.max() + pad), aspect="equal",
           xlabel="x [m]" if flat is not None else "horizontal distance from the start towards the goal [m]",
           ylabel="y [m]" if flat is not None else "height z [m]",
           title=(f"voxel layer at z = {flat:.2f} m" if flat is not None else "vertical plane through start and goal") +
           f", {which}" + (f"\npaths drawn on the plane ({off:.2f} m off it at most)" if off > 0.05 else ""))
    ax.legend(fontsize=8.5, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2)


def _why_more(p: dict, payload_kg: float) -> str:
    """A path that holds through voxels below its payload: why, in words ('' otherwise)."""
    vox = p["g"].voxel_kg.to_numpy(float)
    if not p["holds"] or not (vox < payload_kg).any():
        return ""
    return (f"\nthrough voxels of down to {np.nanmin(vox):,.0f} kg (each one's least over all its points and "
            f"directions):\nits own states, along its own line on its branch, carry ≥ {p['weakest']:,.0f} kg")


def _profile(ax, name: str, p: dict, payload_kg: float) -> None:
    """One path's own capacity, state by state, against distance travelled; the voxels' values under it and the
    payload; red where it is below; grey after tracking was lost."""
    g, colour = p["g"], PATH_STYLE.get(name, {}).get("color", "black")
    n = len(g) if p["lost"] is None else p["lost"]
    s, cap = g.distance_m.to_numpy()[:n], p["cap"][:n]
    along, vox = g.voxel_along_kg.to_numpy(float)[:n], g.voxel_kg.to_numpy(float)[:n]
    top = float(np.nanmax(np.r_[cap[np.isfinite(cap)], along[np.isfinite(along)], payload_kg]))
    ceiling = 1.08 * top
    ax.plot(s, vox, color="0.6", lw=1)
    ax.plot(s, along, color=colour, lw=1.2, ls="--")
    ax.plot(s, np.where(np.isfinite(cap), cap, np.nan), color=colour, lw=3, zorder=5)
    ax.plot(s, np.where(np.isinf(cap), ceiling, np.nan), color=colour, lw=1.2, zorder=5)
    ax.axhline(payload_kg, color="tab:red", lw=1.5)
    ax.fill_between(s, 0, 1, where=p["below"][:n], color="tab:red", alpha=0.15, transform=ax.get_xaxis_transform(),
                    lw=0, step="mid")
    gap = np.isnan(vox) & np.isfinite(np.r_[np.nan, vox[:-1]])  # where the map stops reaching the path
    for i in np.flatnonzero(gap)[:1]:
        ax.annotate("voxels beyond: not reached on\nthis configuration (white at left)", (s[i], 0.55),
                    xycoords=ax.get_xaxis_transform(), fontsize=8.5, color="0.35", ha="left")
    if p["lost"] is not None:
        at, end = g.distance_m.iloc[p["lost"]], g.distance_m.iloc[-1]
        ax.axvspan(at, end, color="0.85", lw=0)
        ax.text((at + end) / 2, 0.5, f"tracking lost at {at:.2f} m:\nthe rest of the line is not executed",
                transform=ax.get_xaxis_transform(), fontsize=9, ha="center", va="center")
    k = p["k"]
    ax.plot(s[k], cap[k], "X", ms=11, mfc="white" if cap[k] >= payload_kg else "tab:red", mec="black", zorder=7,
            clip_on=False)
    right = s[k] > 0.75 * np.nanmax(g.distance_m)  # its label on the side with room
    ax.annotate(f"{cap[k]:,.0f} kg", (s[k], cap[k]), xytext=(-8 if right else 8, 6), textcoords="offset points",
                fontsize=9, ha="right" if right else "left", bbox=dict(fc="white", ec="none", alpha=0.85, pad=1),
                zorder=7)
    ax.set(ylim=(-0.04 * top, 1.14 * top), ylabel="capacity [kg]")
    ticks = [t for t in ax.get_yticks() if 0 <= t <= 1.01 * top]
    ax.set_yticks(ticks + [ceiling], [f"{t:g}" for t in ticks] + ["∞"])
    ax.set_title(_verdict(name, p, payload_kg) + _why_more(p, payload_kg), fontsize=9.5,
                 color="black" if p["holds"] else "tab:red")
    ax.grid(alpha=0.3)


def workspace_paths(main: pd.DataFrame, ts: pd.DataFrame, payload_kg: float, out_png: str | Path, which: str,
                    no_path: str = "", planner: str = "") -> None:
    """Does each path carry ``payload_kg``, where along it does it fail, and why may it cross voxels the map says
    carry less? Left: the voxels of ``main`` (the map of the arm's configuration, with ``capacity_best_axis_kg``:
    the best of its 13 grid axes) on the vertical plane through start and goal (the horizontal layer when the
    paths stay in one), in three classes for the payload, 0 kg voxels hatched, the paths (red where a state is
    below the payload) and their weakest states. Right, one panel per path: its own capacity state by state
    (``ts`` column ``state_capacity_kg``: along its direction at its timed motion; cruising it is unbounded)
    against ``distance_m`` travelled, with the map's values of the voxel under it (``voxel_kg``: least over every
    direction; ``voxel_along_kg``: along the grid axis nearest its direction) and the payload. ``which``: the
    map's name; ``no_path``: why there is no planned path ('' when there is one); ``planner``: what the planner
    looks for, in words (the title says it when the paths are compared)."""
    paths = _path_table(ts, payload_kg)
    fig = plt.figure(figsize=(16, 8.4), layout="constrained")
    sub = fig.subfigures(1, 2, width_ratios=[1.1, 1])
    ax, axes = sub[0].subplots(), sub[1].subplots(len(paths), 1, sharex=True, squeeze=False)[:, 0]
    _plane(ax, main, ts, paths, payload_kg, which)
    for a, (name, p) in zip(axes, paths.items()):
        _profile(a, name, p, payload_kg)
    axes[-1].set_xlabel("distance travelled along the path [m]")
    handles = [plt.Line2D([], [], color="0.3", lw=3, label="the path's own capacity, each state of its timed motion "
                          "along its direction (verified)"),
               plt.Line2D([], [], color="0.3", lw=1.2, label="… unbounded while it cruises (constant velocity: the "
                          "payload adds no load)"),
               plt.Line2D([], [], color="0.3", lw=1.2, ls="--", label="voxel under it, along the grid axis nearest "
                          "the path's direction (map: least over the voxel's points)"),
               plt.Line2D([], [], color="0.6", lw=1, label="voxel under it, least over every direction (map)"),
               plt.Line2D([], [], color="tab:red", lw=1.5, label=f"payload {payload_kg:g} kg (red shading: below it)")]
    sub[1].legend(handles=handles, loc="outside lower center", fontsize=8.5)
    fig.suptitle(f"Carrying {payload_kg:g} kg on {which}: {_story(paths, payload_kg, planner, no_path)}",
                 fontsize=12, color="black" if any(p["holds"] for p in paths.values()) else "tab:red")
    save(fig, out_png)
