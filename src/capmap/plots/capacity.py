"""Figures of the capacity map: the map on the task's plane, one verified task's workspace (does each path carry
its payload; why it may cross voxels the map says carry less), and the loads over time against their limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.colors import BoundaryNorm, ListedColormap

from capmap.plots.common import plt, save

__all__ = ["capacity_map", "workspace_paths", "load_series", "load_label", "PATH_STYLE"]

PATH_STYLE = {"direct": {"color": "black", "ls": "--", "label": "direct line"},
              "planned": {"color": "tab:blue", "ls": "-", "label": "planned path"}}
ENDS = {"start": dict(marker="o", ms=10), "goal": dict(marker="*", ms=15)}  # white, black edge: on any colour
# the workspace figure's voxel classes for a payload M (least over every direction; best of the 13 grid axes)
CLASSES = (("carries M in every direction", "#1b7837"), ("carries M along some grid axes only", "#a6dba0"),
           ("carries M along no grid axis", "#d9d9d9"))


def _volume(m: pd.DataFrame, values: np.ndarray) -> np.ndarray:
    """(nx, ny, nz) array of ``values`` (one per row of the map ``m``) on its grid, NaN where not reached."""
    vol = np.full(m.attrs["capmap"]["grid"]["shape"], np.nan)
    r = (m.n_reachable > 0).to_numpy()
    vol[m.i.to_numpy()[r], m.j.to_numpy()[r], m.k.to_numpy()[r]] = np.asarray(values, float)[r]
    return vol


def _cut(vol: np.ndarray, grid: dict, a: np.ndarray, b: np.ndarray, layer_z: float | None = None):
    """The values of ``vol`` on a plane: the vertical plane through ``a`` and ``b`` (abscissa u: the distance
    from a along a->b's horizontal direction, ordinate z), or the horizontal layer holding ``layer_z`` (x, y).
    Returns the image, its imshow extent and project(xyz (n, 3)) -> (abscissa, ordinate, distance off the plane)."""
    dx, lo, shape = grid["edge_m"], np.asarray(grid["lower_m"], float), np.asarray(grid["shape"])
    if layer_z is not None:
        k = int(np.clip(np.floor((layer_z - lo[2]) / dx), 0, shape[2] - 1))
        zc = lo[2] + (k + 0.5) * dx
        return (vol[:, :, k].T, [lo[0], lo[0] + shape[0] * dx, lo[1], lo[1] + shape[1] * dx],
                lambda p: (p[:, 0], p[:, 1], np.abs(p[:, 2] - zc)))
    d = (b - a)[:2]
    d = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-9 else np.array([1.0, 0.0])
    n = np.array([-d[1], d[0]])
    reach = np.linalg.norm(shape[:2] * dx) + np.linalg.norm(a[:2] - lo[:2])  # beyond the grid: cropped by the caller
    u = np.arange(-reach, reach, dx / 2) + dx / 4
    z = lo[2] + np.arange(0, shape[2] * dx, dx / 2) + dx / 4
    U, Z = np.meshgrid(u, z)
    idx = np.floor((np.dstack([a[:2] + U[..., None] * d, Z]) - lo) / dx).astype(int)
    ok = np.all((idx >= 0) & (idx < shape), axis=-1)
    img = np.full(U.shape, np.nan)
    img[ok] = vol[idx[ok][:, 0], idx[ok][:, 1], idx[ok][:, 2]]
    return (img, [u[0] - dx / 4, u[-1] + dx / 4, z[0] - dx / 4, z[-1] + dx / 4],
            lambda p: ((p[:, :2] - a[:2]) @ d, p[:, 2], np.abs((p[:, :2] - a[:2]) @ n)))


def _hatch_zero(ax, zero: np.ndarray, extent) -> None:
    """Hatch the cells of a cut where ``zero`` is true (the voxel's least over every direction is 0 kg)."""
    if np.any(zero):
        ax.contourf(np.where(zero, 1.0, np.nan), levels=[0.5, 1.5], colors="none", hatches=["xxx"], extent=extent,
                    origin="lower")
        ax.fill([], [], fc="none", ec="0.2", hatch="xxx", label="0 kg in some direction (a singular surface crosses "
                                                                "the voxel), hatched")


def _ends(ax, project, start: np.ndarray, goal: np.ndarray) -> None:
    for name, pos in (("start", start), ("goal", goal)):
        h, v, _ = project(np.atleast_2d(pos))
        ax.plot(h, v, ls="none", mfc="white", mec="black", mew=1.5, zorder=12, **ENDS[name])
        ax.annotate(name, (h[0], v[0]), xytext=(7, 7), textcoords="offset points", fontsize=9, weight="bold",
                    bbox=dict(fc="white", ec="none", alpha=0.8, pad=1), zorder=12)


def capacity_map(vox: pd.DataFrame, view, out_png: str | Path, op: pd.DataFrame | None = None,
                 configuration: str = "", paths=()) -> None:
    """The map for people. Left, how much: the share of the reachable voxels that carry a payload M on the
    arm's ``configuration`` (``op``, :func:`capmap.capacity.tables.configuration_voxels`) and for any
    configuration (the all-branch bound ``vox``). Middle, where: that map's voxels on the vertical plane
    through the task's start and goal (both on it), coloured by capacity (the least over the voxel's points
    and every motion direction), the task payloads as labelled contours, 0 kg voxels hatched; right, the
    same plane around the task with ``paths`` ((label, (n, 3) m, plot style) each; a label says what the
    path itself carries along its own direction). ``view``: a
    :class:`capmap.stages.capacity_figures.MapView` (start_m, goal_m, payloads_kg)."""
    main = vox if op is None else op
    which = f"configuration {configuration} (the arm's)" if op is not None else "any configuration"
    grid = vox.attrs["capmap"]["grid"]
    fig, axes = plt.subplots(1, 3, figsize=(19, 7.6), width_ratios=[0.85, 1.1, 1.1], layout="constrained")
    _share_panel(axes[0], main, vox if op is not None else None, which, view.payloads_kg, grid["edge_m"])
    cap = main.capacity_kg.to_numpy()
    vmax = float(np.nanmax(np.r_[cap[main.n_reachable > 0], 1.0]))
    img, extent, project = _cut(_volume(main, cap), grid, view.start_m, view.goal_m)
    levels = [m for m in view.payloads_kg if np.nanmin(img, initial=np.inf) < m <= np.nanmax(img, initial=-np.inf)]
    off = 0.0
    for ax in axes[1:]:
        im = ax.imshow(img, origin="lower", cmap="viridis", vmin=0.0, vmax=vmax, extent=extent, interpolation="nearest")
        _hatch_zero(ax, img == 0, extent)
        if levels:
            cs = ax.contour(np.where(np.isnan(img), -1.0, img), levels=levels, colors="white", linewidths=1.6,
                            extent=extent, origin="lower")
            ax.clabel(cs, fmt=lambda m: f"{m:g} kg", fontsize=9)
        for name, xyz, style in paths:
            h, v, o = project(np.asarray(xyz, float).reshape(-1, 3))
            off = max(off, float(np.max(o, initial=0.0)))
            ax.plot(h, v, lw=3 if style.get("ls", "-") == "-" else 2.2, label=name, zorder=10, **style)
        _ends(ax, project, view.start_m, view.goal_m)
        ax.set(xlabel="horizontal distance from the start towards the goal [m]", ylabel="height z [m]", aspect="equal")
    rows, cols = np.flatnonzero(np.isfinite(img).any(axis=1)), np.flatnonzero(np.isfinite(img).any(axis=0))
    h, v = np.linspace(*extent[:2], img.shape[1] + 1), np.linspace(*extent[2:], img.shape[0] + 1)
    if len(rows):
        axes[1].set(xlim=(h[cols[0]], h[cols[-1] + 1]), ylim=(v[rows[0]], v[rows[-1] + 1]))
    task = np.vstack([np.column_stack(project(np.asarray(x, float).reshape(-1, 3))[:2])
                      for x in [view.start_m, view.goal_m] + [x for _, x, _ in paths]])
    lo_t, hi_t = task.min(axis=0) - 4 * grid["edge_m"], task.max(axis=0) + 4 * grid["edge_m"]
    axes[2].set(xlim=(lo_t[0], hi_t[0]), ylim=(lo_t[1], hi_t[1]))
    axes[1].indicate_inset_zoom(axes[2], edgecolor="black")
    missing = [f"{m:g} kg" for m in view.payloads_kg if m not in levels]
    axes[1].set_title("Where: vertical plane through start and goal\nwhite lines: the task payloads carried in every "
                      "direction" + (f" ({', '.join(missing)}: nowhere here)" if missing else ""), fontsize=10.5)
    axes[2].set_title("Around the task: the paths" + (f" (drawn on the plane, {off:.2f} m off it at most)"
                                                      if off > 0.05 * grid["edge_m"] else "") +
                      "\na path needs only its own direction: it can carry more than the voxels it crosses", fontsize=10.5)
    cb = fig.colorbar(im, ax=axes[1:], shrink=0.8, label="voxel capacity [kg] (least over its points and every "
                                                          "direction; white: not reached)")
    for m in [m for m in view.payloads_kg if m <= vmax]:
        cb.ax.axhline(m, color="white", lw=2)
    axes[2].legend(fontsize=8.5, loc="upper center", bbox_to_anchor=(0.5, -0.1))
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


def _path_table(ts: pd.DataFrame, payload_kg: float) -> dict:
    """Per path: its samples, the weakest tracked state (kg, its row), where tracking was lost (row; None),
    whether it stays in its joint range and carries ``payload_kg``."""
    out = {}
    for name, g in ts.groupby("path", observed=True, sort=False):
        g = g.reset_index(drop=True)
        ok = g.tracked.to_numpy(bool) if "tracked" in g else np.ones(len(g), bool)
        cap = np.where(ok, g.state_capacity_kg.to_numpy(float), np.nan)
        k = int(np.nanargmin(cap)) if np.isfinite(cap).any() else 0
        p = dict(g=g, weakest=float(cap[k]) if np.isfinite(cap).any() else 0.0, k=k,
                 lost=None if ok.all() else int(np.flatnonzero(~ok)[0]),
                 in_range=bool(g.in_joint_range.all()) if "in_joint_range" in g else True)
        out[name] = {**p, "holds": p["weakest"] >= payload_kg and p["lost"] is None and p["in_range"]}
    return out


def _verdict(name: str, p: dict, payload_kg: float) -> str:
    label = PATH_STYLE.get(name, {}).get("label", name)  # e.g. "planned path holds: weakest segment 4149 kg (+3.7 %...)"
    if p["lost"] is not None:
        return f"{label} FAILS: tracking lost at {p['g'].t_s.iloc[p['lost']]:.1f} s (singular), {p['weakest']:.0f} kg"
    return (f"{label} {'holds' if p['holds'] else 'FAILS'}: weakest segment {p['weakest']:.0f} kg "
            f"({100 * (p['weakest'] / payload_kg - 1):+.1f} % margin)" + ("" if p["in_range"] else
                                                                       ", but it leaves its joint range"))


def workspace_paths(main: pd.DataFrame, ts: pd.DataFrame, payload_kg: float, out_png: str | Path, which: str,
                    no_path: str = "") -> None:
    """Does each path carry ``payload_kg``, and why may it cross voxels the map says carry less? Left: the
    voxels of ``main`` (the map of the arm's configuration, with ``capacity_best_axis_kg``: the best of its
    13 grid axes) on the vertical plane through start and goal (the horizontal layer when the paths stay in
    one), in three classes for the payload, 0 kg voxels hatched, the paths and their weakest states. Right,
    one panel per path: its own capacity along its direction (``ts`` column ``segment_capacity_kg``) against
    ``distance_m`` travelled, with the map's values of the voxel under it (``voxel_kg``: least over every
    direction; ``voxel_along_kg``: along the grid axis nearest its direction) and the payload.
    ``which``: the map's name; ``no_path``: why there is no planned path ('' when there is one)."""
    paths = _path_table(ts, payload_kg)
    fig = plt.figure(figsize=(16, 7.8), layout="constrained")
    sub = fig.subfigures(1, 2, width_ratios=[1.15, 1])
    ax, axes = sub[0].subplots(), sub[1].subplots(len(paths), 1, sharex=True, squeeze=False)[:, 0]
    grid = main.attrs["capmap"]["grid"]
    start, goal = next(iter(paths.values()))["g"][["x_m", "y_m", "z_m"]].to_numpy()[[0, -1]]
    cls = np.select([main.capacity_kg >= payload_kg, main.capacity_best_axis_kg >= payload_kg], [0.0, 1.0], 2.0)
    flat = start[2] if np.ptp(ts.z_m.to_numpy()) <= grid["edge_m"] / 2 else None
    img, extent, project = _cut(_volume(main, cls), grid, start, goal, flat)
    ax.imshow(img, origin="lower", extent=extent, interpolation="nearest", cmap=ListedColormap([c for _, c in CLASSES]),
              norm=BoundaryNorm([-0.5, 0.5, 1.5, 2.5], 3))
    for label, colour in CLASSES + (("not reached on this configuration", "white"),):
        ax.fill([], [], fc=colour, ec="0.5", label=label.replace("M", f"{payload_kg:g} kg"))
    _hatch_zero(ax, _cut(_volume(main, main.capacity_kg.to_numpy() == 0), grid, start, goal, flat)[0] == 1, extent)
    off = 0.0
    for name, p in paths.items():
        h, v, o = project(p["g"][["x_m", "y_m", "z_m"]].to_numpy())
        off = max(off, float(o.max()))
        ax.plot(h, v, lw=3, zorder=10, **PATH_STYLE.get(name, {"label": name}))
        ax.plot(h[p["k"]], v[p["k"]], "X", ms=12, mfc="white" if p["holds"] else "tab:red", mec="black", zorder=11)
        ax.annotate(f"{p['weakest']:.0f} kg", (h[p["k"]], v[p["k"]]), xytext=(8, -14), textcoords="offset points",
                    fontsize=9, bbox=dict(fc="white", ec="none", alpha=0.85, pad=1), zorder=11)
    ax.plot([], [], "X", ms=9, mfc="white", mec="black", label="weakest state of each path (red: below the payload)")
    _ends(ax, project, start, goal)
    h, v, _ = project(ts[["x_m", "y_m", "z_m"]].to_numpy())
    pad = 3 * grid["edge_m"]
    ax.set(xlim=(h.min() - pad, h.max() + pad), ylim=(v.min() - pad, v.max() + pad), aspect="equal",
           xlabel="x [m]" if flat is not None else "horizontal distance from the start towards the goal [m]",
           ylabel="y [m]" if flat is not None else "height z [m]",
           title=(f"voxel layer at z = {flat:.2f} m" if flat is not None else "vertical plane through start and goal") +
           f", {which}" + (f"\npaths drawn on the plane ({off:.2f} m off it at most)" if off > 0.05 else ""))
    ax.legend(fontsize=8.5, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2)
    for a, (name, p) in zip(axes, paths.items()):
        _profile(a, name, p, payload_kg)
    axes[-1].set_xlabel("distance travelled along the path [m]")
    handles = [plt.Line2D([], [], color="0.3", lw=3, label="the path's own capacity along its direction "
                          "(weakest state of each segment, verified)"),
               plt.Line2D([], [], color="0.3", lw=1.2, ls="--", label="voxel under it, along the grid axis nearest "
                          "the path's direction (map: least over the voxel's points)"),
               plt.Line2D([], [], color="0.6", lw=1, label="voxel under it, least over every direction (map)"),
               plt.Line2D([], [], color="tab:red", lw=1.5, label=f"payload {payload_kg:g} kg")]
    sub[1].legend(handles=handles, loc="outside lower center", fontsize=8.5)
    verdicts = [f"{PATH_STYLE.get(n, {}).get('label', n)} {'holds' if p['holds'] else 'fails'}"
                for n, p in reversed(paths.items())]
    fig.suptitle(f"Carrying {payload_kg:g} kg on {which}: {', '.join(verdicts)}" + (
        f" (no planned path: {no_path})" if no_path else ""), fontsize=12.5,
        color="black" if any(p["holds"] for p in paths.values()) else "tab:red")
    save(fig, out_png)


def _profile(ax, name: str, p: dict, payload_kg: float) -> None:
    """One path's capacity against distance travelled, the voxels' values under it and the payload."""
    g, colour = p["g"], PATH_STYLE.get(name, {}).get("color", "black")
    g = g.iloc[: len(g) if p["lost"] is None else p["lost"]]
    s, seg = g.distance_m.to_numpy(), g.segment_capacity_kg.to_numpy(float)
    ax.plot(s, g.voxel_kg, color="0.6", lw=1)
    ax.plot(s, g.voxel_along_kg, color=colour, lw=1.2, ls="--")
    ax.plot(s, seg, color=colour, lw=3)
    ax.axhline(payload_kg, color="tab:red", lw=1.5)
    ax.fill_between(s, 0, 1, where=seg < payload_kg, color="tab:red", alpha=0.12, transform=ax.get_xaxis_transform(),
                    lw=0, step="mid")
    if p["lost"] is not None:
        ax.axvspan(s[-1], p["g"].distance_m.iloc[-1], color="0.85", lw=0)
        ax.text(s[-1], 0.5, "  tracking lost: no motion after it", transform=ax.get_xaxis_transform(), fontsize=9)
    top = np.nanmax(np.r_[seg[np.isfinite(seg)], g.voxel_along_kg, payload_kg])
    ax.set(ylim=(0, 1.12 * top), ylabel="capacity [kg]")
    ax.set_title(_verdict(name, p, payload_kg), color="black" if p["holds"] else "tab:red", fontsize=10.5)
    ax.grid(alpha=0.3)


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


def load_series(ts: pd.DataFrame, columns: list[str], limits: dict, title: str, out_png: str | Path) -> None:
    """One panel per path: the given loads over time against their ±limits (dotted: one grey pair when all
    share one limit, else in the colour of its load), the verdict in the panel's and the figure's title (the
    peak as % of its limit, the load that reaches it; the other limits of ``limits`` a path exceeds named),
    what breaks a limit shaded red, the time tracking was lost marked (no motion after it), a spike far above
    the limits drawn off scale with its peak written; legends beside the panels, off the curves."""
    paths = list(ts.path.cat.categories if hasattr(ts.path, "cat") else ts.path.unique())
    quantity, unit = next(v for k, v in QUANTITY.items() if columns[0].startswith(k))
    fig, axes = plt.subplots(len(paths), 1, figsize=(12.5, 3.4 * len(paths) + 0.8), squeeze=False, sharex=True,
                             layout="constrained")
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    same = len({limits[k] for k in columns}) == 1
    heads = []
    for ax, name in zip(axes[:, 0], paths):
        t = (g := ts[ts.path == name]).t_s.to_numpy()
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
        if over.any():
            ax.fill_between(t, -top, top, where=over, color="tab:red", alpha=0.15, step="mid", lw=0,
                            label="over its limit")
        if big > top:
            ax.annotate(f"off scale: {100 * peak:.0f} % of its limit at t = {t_peak:.1f} s", xy=(t_peak, 0.9 * top),
                        xytext=(10, 0), textcoords="offset points", fontsize=8.5, color="tab:red", va="center")
        if t_lost is not None:
            ax.axvline(t_lost, color="black", lw=1.5)
            ax.axvspan(t_lost, t[-1], color="0.85", alpha=0.6, lw=0)
            ax.text(t_lost, -0.5 * top, "  tracking lost: no motion after it", fontsize=9, va="center")
        label = PATH_STYLE.get(name, {}).get("label", name)
        worst = f"{load_label(at)} at {100 * peak:.0f} % of its {limits[at]:g} {unit} limit (t = {t_peak:.1f} s)"
        verdict = (f"FAILS: tracking lost at {t_lost:.1f} s (singular); before it {worst}" if t_lost is not None
                   else f"EXCEEDS a limit: {worst}" if peak > 1 else f"within limits: peak {worst}")
        ok = peak <= 1 and t_lost is None
        names, also = _also(g, columns, limits)
        heads.append(f"{label} {'within limits' if ok else 'FAILS'} ({100 * peak:.0f} %)"
                     + (f" but fails on {', '.join(names)}" if ok and names else ""))
        ax.set(ylabel=f"{quantity} [{unit}]")
        ax.set_title(f"{label} {verdict}" + (f"\n{'but' if ok else 'it also'} exceeds {also}" if also else ""),
                     fontsize=10.5, color="black" if ok else "tab:red")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    axes[-1, 0].set_xlabel("time t [s]")
    fig.suptitle(f"{title}: " + "; ".join(heads) + ("" if "planned" in paths else " (no planned path at this payload)"),
                 fontsize=12)
    save(fig, out_png)
