"""Figures of the capacity map: the map itself, the workspace with the verified paths, and
the loads over time against their limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.plots.common import plt, save

__all__ = ["capacity_map", "workspace_paths", "load_series", "load_label", "PATH_STYLE"]


def _layer(vox: pd.DataFrame, k: int) -> tuple[np.ndarray, list[float], float]:
    """Capacity image (ny, nx) of voxel layer ``k`` (NaN: unreachable), its imshow extent and the
    height of its centres [m]."""
    grid = vox.attrs["capmap"]["grid"]
    dx, lo, (nx, ny, _) = grid["edge_m"], grid["lower_m"], grid["shape"]
    sl = vox[vox.k == k]
    img = np.full((ny, nx), np.nan)
    img[sl.j.to_numpy(), sl.i.to_numpy()] = np.where(sl.n_reachable > 0, sl.capacity_kg, np.nan)
    return img, [lo[0], lo[0] + nx * dx, lo[1], lo[1] + ny * dx], lo[2] + (k + 0.5) * dx


def _layer_of(vox: pd.DataFrame, z_m: float) -> int:
    grid = vox.attrs["capmap"]["grid"]
    return int(np.clip(np.floor((z_m - grid["lower_m"][2]) / grid["edge_m"]), 0, grid["shape"][2] - 1))


def _layer_panel(ax, vox: pd.DataFrame, k: int, view, vmax: float, what: str, paths=()):
    """One horizontal voxel layer ``k`` of a map coloured by capacity (0 kg voxels crossed in red),
    the task payloads as contours, start and goal, the planned paths (x-y, m) drawn over it."""
    pay_colors = ["white", "tab:red", "magenta", "orange"]
    img, extent, z = _layer(vox, k)
    im = ax.imshow(img, origin="lower", cmap="viridis", vmin=0.0, vmax=vmax, extent=extent, interpolation="nearest")
    drawn = []
    lo, hi = np.nanmin(img, initial=np.inf), np.nanmax(img, initial=-np.inf)
    for n, m in enumerate(view.payloads_kg):
        if lo < m <= hi:
            ax.contour(np.where(np.isnan(img), -1.0, img), levels=[m], colors=pay_colors[n % 4], linewidths=1.3,
                       extent=extent, origin="lower")
            drawn.append(f"{m:g} kg ({pay_colors[n % 4]})")
        else:
            drawn.append(f"{m:g} kg: {'no voxel carries it' if hi < m else 'every voxel carries it'}")
    sl = vox[(vox.k == k) & (vox.capacity_kg == 0)]
    if len(sl):
        ax.plot(sl.x_m, sl.y_m, "x", color="tab:red", ms=4, mew=1, label="0 kg")
    for name, xy, style in paths:
        ax.plot(xy[:, 0], xy[:, 1], lw=1.4, label=name, **style)
    for pos, name, mk, col in ((view.start_m, "start", "o", "tab:green"), (view.goal_m, "goal", "*", "tab:orange")):
        inside = _layer_of(vox, pos[2]) == k
        ax.plot(pos[0], pos[1], mk, ms=11, mfc=col if inside else "none", mec=col, mew=2,
                label=f"{name}{'' if inside else ' (projected)'}")
    ax.set(xlabel="x [m]", ylabel="y [m]", title=f"{what}, layer z = {z:.2f} m\ncontours: " + "; ".join(drawn))
    ax.xaxis.set_major_locator(plt.MaxNLocator(6))
    ax.legend(fontsize=7, loc="lower left", framealpha=0.9)
    return im


def capacity_map(vox: pd.DataFrame, view, out_png: str | Path, op: pd.DataFrame | None = None,
                 configuration: str = "", paths=()) -> None:
    """The map for people. With ``op`` (the map of the arm's ``configuration``,
    :func:`capmap.capacity.tables.configuration_voxels`): the share of reachable voxels carrying each
    payload on that configuration and for any configuration (the all-branch bound ``vox``), the
    start's, goal's and fullest voxel layers of the arm's configuration, and the start's and goal's
    layers of the bound; without it, the bound's. Coloured by capacity on one scale, 0 kg voxels
    crossed in red (a singular surface of the map's configurations crosses them), the task payloads
    as contour lines, start, goal and ``paths`` ((label, (n, 3) m, plot style) each) drawn.
    ``view``: a :class:`capmap.stages.capacity_figures.MapView` (start_m, goal_m, payloads_kg)."""
    main = vox if op is None else op
    reach = main[main.n_reachable > 0]
    bound = vox[vox.n_reachable > 0]
    grid = vox.attrs["capmap"]["grid"]
    fig, axes = plt.subplots(2, 3, figsize=(17, 10.5), layout="constrained")
    cap = np.sort(reach.capacity_kg.to_numpy())
    cap_b = np.sort(bound.capacity_kg.to_numpy())
    vmax = float(max(cap[-1] if len(cap) else 0.0, cap_b[-1] if len(cap_b) else 0.0)) or 1.0
    mmax = 1.05 * max(vmax, *view.payloads_kg)
    ax = axes[0, 0]
    name = f"configuration {configuration} (the arm's)" if op is not None else "any configuration (every IK branch)"
    ax.step(cap, 1.0 - np.arange(len(cap)) / max(len(cap), 1), where="post", color="tab:blue", label=name)
    if op is not None:
        ax.step(cap_b, 1.0 - np.arange(len(cap_b)) / max(len(cap_b), 1), where="post", color="0.4", ls="--",
                label="any configuration: the bound (least over every IK branch)")
    for n, m in enumerate(view.payloads_kg):
        share = float(np.mean(cap >= m)) if len(cap) else 0.0
        ax.axvline(m, color="k", ls=":", lw=1)
        right = m > 0.7 * mmax
        ax.annotate(f"{m:g} kg: {100 * share:.0f}% of voxels", (m, share), xytext=(-6 if right else 6, 6 + 14 * n),
                    textcoords="offset points", fontsize=9, ha="right" if right else "left")
    ax.set(xlabel="payload M [kg]", ylabel="share of its reachable voxels carrying M", ylim=(0, 1.02), xlim=(0, mmax),
           title=f"{len(reach):,} voxels reachable on {configuration or 'any configuration'} (edge {grid['edge_m']:g} m)"
                 "\ndotted: task payloads (share: the arm's configuration)")
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    what = f"{configuration} (the arm's)" if op is not None else "any configuration"
    panels = [(axes[0, 1], main, _layer_of(vox, view.start_m[2]), f"{what}: start's"),
              (axes[0, 2], main, _layer_of(vox, view.goal_m[2]), f"{what}: goal's")]
    if len(reach):
        panels.append((axes[1, 0], main, int(reach.k.value_counts().idxmax()), f"{what}: fullest"))
    if op is not None:
        panels += [(axes[1, 1], vox, _layer_of(vox, view.start_m[2]), "any configuration (bound): start's"),
                   (axes[1, 2], vox, _layer_of(vox, view.goal_m[2]), "any configuration (bound): goal's")]
    used = {id(p[0]) for p in panels} | {id(axes[0, 0])}
    im = None
    for ax, m_, k, title in panels:
        im = _layer_panel(ax, m_, k, view, vmax, title, paths)
    for ax in axes.ravel():
        if id(ax) not in used:
            ax.axis("off")
    if im is not None:
        cb = fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.6,
                          label="voxel capacity [kg] (white: not reached; red x: 0 kg; black lines: task payloads)")
        for m in view.payloads_kg:
            if m <= vmax:
                cb.ax.axhline(m, color="k", lw=1.5)
    head = (f"on the arm's configuration {configuration} (its start's: it keeps it while it crosses no singular surface); "
            "below right: the bound for any configuration" if op is not None else
            "on every IK branch (no configuration maps without voxels.refine)")
    note = ("\nplanned paths are verified along their own directions (verify/summary.csv): a path can carry its payload "
            "across voxels whose least over every direction is below it" if len(paths) > 1 else "")
    fig.suptitle("Dynamic load-carrying capacity of each voxel (the least over its points and every motion direction)\n"
                 + head + note, fontsize=12)
    save(fig, out_png)


PATH_STYLE = {"direct": {"color": "tab:red", "ls": "--", "label": "direct line"},
              "planned": {"color": "black", "ls": "-", "label": "planned path"}}


def workspace_paths(vox: pd.DataFrame, ts: pd.DataFrame, payload_kg: float, out_png: str | Path,
                    no_path: str = "", op: pd.DataFrame | None = None, configuration: str = "") -> None:
    """Voxels near the paths coloured by capacity (grey: below the payload), the direct line and
    the planned path in 3D; and the x-y voxel layer of the goal. The map drawn is ``op``, that of the
    arm's ``configuration`` (the paths' start's), when given, else the all-branch bound ``vox``. A
    voxel's value is its least over every motion direction, so a path can carry the payload across
    voxels below it: the legend says so with the path's own weakest state. ``no_path``: why there is
    no planned path (shown in both panels), '' when there is one."""
    main = vox if op is None else op
    which = f"configuration {configuration}" if op is not None else "every IK branch"
    reach = main[main.n_reachable > 0]
    dx = vox.attrs["capmap"]["grid"]["edge_m"]
    lo = ts[["x_m", "y_m", "z_m"]].min().to_numpy() - 1.5 * dx
    hi = ts[["x_m", "y_m", "z_m"]].max().to_numpy() + 1.5 * dx
    xyz = reach[["x_m", "y_m", "z_m"]].to_numpy()
    near = reach[np.all((xyz >= lo) & (xyz <= hi), axis=1)]
    vmax = float(max(np.nanmax(reach.capacity_kg), payload_kg)) if len(reach) else 1.0
    fig = plt.figure(figsize=(14, 6.4))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    strong = near[near.capacity_kg >= payload_kg]
    weak = near[near.capacity_kg < payload_kg]
    sc = ax.scatter(strong.x_m, strong.y_m, strong.z_m, c=strong.capacity_kg, s=8, cmap="viridis", vmin=0, vmax=vmax,
                    alpha=0.25, depthshade=False, label=f"voxel >= {payload_kg:g} kg" if len(strong) else None)
    sc_w = ax.scatter(weak.x_m, weak.y_m, weak.z_m, c=weak.capacity_kg, s=12, marker="x", cmap="viridis", vmin=0,
                      vmax=vmax, alpha=0.5, depthshade=False, label=f"x: voxel < {payload_kg:g} kg" if len(weak) else None)
    sc = sc if len(strong) else sc_w
    carried = []
    for name, g in ts.groupby("path", observed=True):
        weakest = np.nanmin(g.state_capacity_kg.to_numpy(), initial=np.inf) if g.state_capacity_kg.notna().any() else 0
        style = dict(PATH_STYLE.get(name, {}))
        style["label"] = f"{style.get('label', name)}: its states carry >= {weakest:.0f} kg"
        ax.plot(g.x_m, g.y_m, g.z_m, lw=2.5, zorder=10, **style)
        if weakest >= payload_kg:
            carried.append(f"{PATH_STYLE.get(name, {}).get('label', name)} ({weakest:.0f} kg)")
    first = ts.iloc[0]
    last = ts[ts.path == ts.path.iloc[0]].iloc[-1]
    ax.scatter([first.x_m], [first.y_m], [first.z_m], c="tab:green", s=60, marker="o", label="start")
    ax.scatter([last.x_m], [last.y_m], [last.z_m], c="tab:orange", s=80, marker="*", label="goal")
    fig.colorbar(sc, ax=ax, shrink=0.7, pad=0.12, label=f"voxel capacity [kg], {which}")
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]", xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
           title=f"voxels near the paths ({which}), {payload_kg:g} kg" + (
               f"\nno planned path: {_short(no_path)}" if no_path else ""))
    if carried and len(weak):
        fig.text(0.01, 0.01, f"Why a verified path crosses voxels below {payload_kg:g} kg: a voxel's value is its least over "
                 f"its points and every motion direction; a path is verified along its own direction, and the states of "
                 f"the {' and the '.join(carried)} carry the payload.", fontsize=8.5, wrap=True)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(plt.MaxNLocator(3))  # a short axis in perspective crowds more labels
    ax.set_box_aspect(hi - lo)
    ax.legend(loc="upper left", fontsize=7, bbox_to_anchor=(0.0, 1.0))
    ax2 = fig.add_subplot(1, 2, 2)
    climb = float(np.ptp(ts.z_m.to_numpy())) if len(ts) else 0.0
    if climb > dx:  # a path that leaves the goal's layer: the vertical section through start and goal shows it
        _section_panel(ax2, fig, main, ts, first, last, payload_kg, vmax, which, no_path)
        save(fig, out_png)
        return
    img, extent, z = _layer(main, _layer_of(main, last.z_m))
    im = ax2.imshow(img, origin="lower", cmap="viridis", vmin=0, vmax=vmax, extent=extent, interpolation="nearest")
    has_edge = np.nanmin(img, initial=np.inf) < payload_kg <= np.nanmax(img, initial=-np.inf)
    if has_edge:
        ax2.contour(np.where(np.isnan(img), -1, img), levels=[payload_kg], colors="white", linewidths=1.2,
                    extent=extent, origin="lower")
    layer = main[(main.k == _layer_of(main, last.z_m)) & (main.n_reachable > 0) & (main.capacity_kg == 0)]
    if len(layer):  # 0 kg (a singular surface crosses the voxel) apart from the colour scale's low end
        ax2.plot(layer.x_m, layer.y_m, "x", color="tab:red", ms=4, mew=1, label="0 kg (singular)")
    for name, g in ts.groupby("path", observed=True):
        ax2.plot(g.x_m, g.y_m, lw=1.5, **PATH_STYLE.get(name, {}))
    ax2.plot(last.x_m, last.y_m, "*", color="tab:orange", ms=12, label="goal")
    ax2.plot(first.x_m, first.y_m, "o", mfc="none", mec="tab:green", mew=2, ms=9, label="start (projected)")
    _capacity_colorbar(fig, im, ax2, which, payload_kg)
    edge = (f"white line: boundary of {payload_kg:g} kg" if has_edge else
            f"no voxel of this layer carries {payload_kg:g} kg" if np.nanmax(img, initial=0) < payload_kg else
            f"every voxel of this layer carries {payload_kg:g} kg")
    ax2.set(xlabel="x [m]", ylabel="y [m]", title=f"goal's voxel layer z = {z:.2f} m, {which}\n{edge}")
    ax2.legend(fontsize=8, loc="lower left")
    _no_path_note(ax2, no_path)
    save(fig, out_png)


def _section_panel(ax, fig, main: pd.DataFrame, ts: pd.DataFrame, first, last, payload_kg: float, vmax: float,
                   which: str, no_path: str) -> None:
    """The voxels' capacity on the vertical plane through start and goal (abscissa: distance along the
    start-goal line's horizontal direction, m; ordinate: z, m), the paths projected onto it: a path that
    climbs over a singular slab shows its detour here, where a top view would flatten it."""
    grid = main.attrs["capmap"]["grid"]
    dx, lo, shape = grid["edge_m"], np.asarray(grid["lower_m"], float), np.asarray(grid["shape"])
    a, b = np.array([first.x_m, first.y_m]), np.array([last.x_m, last.y_m])
    d = b - a
    d = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-9 else np.array([1.0, 0.0])
    u_path = (ts[["x_m", "y_m"]].to_numpy() - a) @ d
    u = np.arange(u_path.min() - 4 * dx, u_path.max() + 4 * dx, dx / 2)
    z = np.arange(lo[2], lo[2] + shape[2] * dx, dx / 2) + dx / 4
    cap = np.full((shape[0], shape[1], shape[2]), np.nan)
    reach = main[main.n_reachable > 0]
    cap[reach.i.to_numpy(), reach.j.to_numpy(), reach.k.to_numpy()] = reach.capacity_kg.to_numpy()
    U, Z = np.meshgrid(u, z)
    P = a + U[..., None] * d
    idx = np.floor((np.dstack([P, Z]) - lo) / dx).astype(int)
    ok = np.all((idx >= 0) & (idx < shape), axis=-1)
    img = np.full(U.shape, np.nan)
    img[ok] = cap[idx[ok][:, 0], idx[ok][:, 1], idx[ok][:, 2]]
    extent = [u[0] - dx / 4, u[-1] + dx / 4, z[0] - dx / 4, z[-1] + dx / 4]
    im = ax.imshow(img, origin="lower", cmap="viridis", vmin=0, vmax=vmax, extent=extent, interpolation="nearest",
                   aspect="equal")
    zero = np.where(img == 0, 1.0, np.nan)
    if np.isfinite(zero).any():
        ax.contourf(U, Z, zero, levels=[0.5, 1.5], colors="none", hatches=["xx"], extent=extent)
        ax.plot([], [], "s", mfc="none", mec="0.2", label="0 kg (singular), hatched")
    if np.nanmin(img, initial=np.inf) < payload_kg <= np.nanmax(img, initial=-np.inf):
        ax.contour(U, Z, np.where(np.isnan(img), -1, img), levels=[payload_kg], colors="white", linewidths=1.2)
    for name, g in ts.groupby("path", observed=True):
        ax.plot((g[["x_m", "y_m"]].to_numpy() - a) @ d, g.z_m, lw=1.5, **PATH_STYLE.get(name, {}))
    ax.plot((b - a) @ d, last.z_m, "*", color="tab:orange", ms=12, label="goal")
    ax.plot(0.0, first.z_m, "o", mfc="none", mec="tab:green", mew=2, ms=9, label="start")
    zp = ts.z_m.to_numpy()
    ax.set_ylim(max(extent[2], zp.min() - 4 * dx), min(extent[3], zp.max() + 4 * dx))
    _capacity_colorbar(fig, im, ax, which, payload_kg)
    ax.set(xlabel="distance along the start-goal direction (horizontal) [m]", ylabel="z [m]",
           title=f"vertical section through start and goal, {which}\nwhite line: boundary of {payload_kg:g} kg")
    ax.xaxis.set_major_locator(plt.MaxNLocator(6))
    ax.legend(fontsize=8, loc="lower left")
    _no_path_note(ax, no_path)


def _no_path_note(ax, no_path: str) -> None:
    """Why there is no planned path, boxed at the top of the panel ('' : nothing)."""
    if no_path:
        ax.text(0.5, 0.97, f"no planned path: {_short(no_path)}", transform=ax.transAxes, ha="center", va="top",
                fontsize=8, bbox=dict(fc="white", ec="tab:red", alpha=0.9), wrap=True)


def _capacity_colorbar(fig, im, ax, which: str, payload_kg: float) -> None:
    """The voxel capacity's colour bar beside ``ax``, the payload marked on it."""
    cb = fig.colorbar(im, ax=ax, label=f"voxel capacity [kg], {which} (white: not reached)")
    cb.ax.axhline(payload_kg, color="k", lw=1.5)


def _short(text: str, n: int = 90) -> str:
    return text if len(text) <= n else text[: n - 1] + "…"


# the quantity and unit of each load column, for axis labels and legends
QUANTITY = {"tau": ("joint torque", "N m"), "base_f": ("base disturbance force", "N"),
            "base_m": ("base disturbance moment", "N m")}


def load_label(column: str) -> str:
    """'tau_j3_nm' -> 'τ joint 3', 'base_fx_n' -> 'F_x', 'base_my_nm' -> 'M_y'."""
    if column.startswith("tau_j"):
        return f"τ joint {column.split('_')[1][1:]}"
    return f"{'F' if column.startswith('base_f') else 'M'}_{column.split('_')[1][1:]}"


def load_series(ts: pd.DataFrame, columns: list[str], limits: dict, title: str, out_png: str | Path) -> None:
    """One panel per path: the given loads over time, each with its +-limit as dotted lines of its
    own colour (one grey pair when all share one limit). What breaks a limit is shaded red and named in
    the panel's title; where tracking was lost (``tracked`` false) the trace ends, a line marks the
    moment and the title says so; a spike far above the limits is drawn off scale (the axis keeps the
    limits readable) with its peak written where it leaves the panel."""
    paths = list(ts.path.cat.categories if hasattr(ts.path, "cat") else ts.path.unique())
    quantity, unit = next(v for k, v in QUANTITY.items() if columns[0].startswith(k))
    fig, axes = plt.subplots(len(paths), 1, figsize=(11, 3.6 * len(paths)), squeeze=False, sharex=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    same = len({limits[k] for k in columns}) == 1  # one pair of grey lines serves all
    for ax, name in zip(axes[:, 0], paths):
        g = ts[ts.path == name]
        t = g.t_s.to_numpy()
        lost = np.flatnonzero(~g.tracked.to_numpy(dtype=bool)) if "tracked" in g else np.array([], int)
        t_lost = t[lost[0]] if len(lost) else None
        lim_max = max(limits[c] for c in columns)
        over = np.zeros(len(g), bool)
        for n, col in enumerate(columns):
            c = colors[n % len(colors)]
            y = g[col].to_numpy(dtype=float)
            ax.plot(t, y, color=c, lw=1.2, label=load_label(col))
            over |= np.abs(np.nan_to_num(y)) > limits[col]
            if not same or n == 0:
                lim = limits[col]
                ax.axhline(lim, color="0.3" if same else c, ls=":", lw=1.2)
                ax.axhline(-lim, color="0.3" if same else c, ls=":", lw=1.2)
        ratios = [np.nanmax(np.abs(g[c]) / limits[c]) for c in columns if np.isfinite(g[c]).any()]
        peak = max(ratios) if ratios else 0.0
        big = max((np.nanmax(np.abs(g[c])) for c in columns if np.isfinite(g[c]).any()), default=0.0)
        top = 1.4 * max(lim_max, big) if big <= 3 * lim_max else 2.5 * lim_max  # a spike beyond 3x: off scale
        ax.set_ylim(-top, top)
        if over.any():
            ax.fill_between(t, -top, top, where=over, color="tab:red", alpha=0.15, step="mid", lw=0,
                            label="over its limit")
        if big > top:
            k = int(np.nanargmax(np.max([np.abs(g[c].to_numpy(dtype=float)) for c in columns], axis=0)))
            ax.annotate(f"off scale: {100 * peak:.0f}% of its limit at t = {t[k]:.1f} s", xy=(t[k], np.sign(
                np.nansum([g[c].to_numpy(dtype=float)[k] for c in columns])) * top * 0.97), xytext=(10, 0),
                textcoords="offset points", fontsize=8, color="tab:red", va="center")
        if t_lost is not None:
            ax.axvline(t_lost, color="black", lw=1.5)
            ax.axvspan(t_lost, t[-1], color="0.85", alpha=0.6, lw=0)
            ax.text(t_lost, 0.5 * top, f"  tracking lost at {t_lost:.1f} s:\n  no motion after it", fontsize=9,
                    va="center")
        lim_note = (f"dotted grey: ±{limits[columns[0]]:g} {unit}" if same else "dotted: ±limit, colour of its load")
        label = PATH_STYLE.get(name, {}).get("label", name)
        verdict = (f"tracking lost at {t_lost:.1f} s; before it, peak {100 * peak:.0f}% of its limit" if t_lost is not None
                   else f"EXCEEDS its limit: peak {100 * peak:.1f}%" if peak > 1 else f"peak {100 * peak:.0f}% of its limit")
        ax.set(ylabel=f"{quantity} [{unit}]", title=f"{label}: {verdict} ({lim_note})")
        ax.title.set_color("tab:red" if peak > 1 or t_lost is not None else "black")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=len(columns) + over.any(), loc="upper right")
    axes[-1, 0].set_xlabel("time t [s]")
    fig.suptitle(title + ("" if "planned" in paths else " (no planned path at this payload: see the summary)"))
    save(fig, out_png)
