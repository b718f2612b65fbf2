"""Figures of the dual-arm assembly: task-constraint errors, safety distances, joints and their
velocities against the limits, the joint torques with the held panel against the effort limits, the
solver's convergence, and the 3D animation."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import meshcat.animation as ma
import numpy as np
import pandas as pd

from capmap.plots.common import legend_beside, limit_gauge, on_top, plt, save
from capmap.plots.scene3d import Overlay, aim, capsule, cylinder, facing, g, hide_helpers, material, new_scene, write_html

__all__ = ["constraint_errors", "distances", "joints", "torques", "convergence", "Surroundings", "Held", "animation"]

SPEC_M = 7e-7  # docs/spec/dual-arm-assembly.md: "the paper's reported result: maximum closed-chain / path error below 7e-7 m"
SPEC = "the spec's reference 7e-7 m\n(docs/spec/dual-arm-assembly.md: the largest\nerror its source paper reports)"
TOLERANCE = "the solver's tolerance {:g} {}\n(config: dualarm.solver.tolerance)"
ZERO = 1e-16  # where an exact zero is drawn on a log scale


def _phases(ax, t_pre: float | None, t_end: float) -> None:
    """The pre-insertion pose (dashed grey, in the legend) and the phases' names in the top 3 % of the axes
    (the figures leave that band free of data)."""
    if t_pre is None:
        return
    ax.axvline(t_pre, color="0.45", lw=0.9, ls="--", label=f"pre-insertion pose ({t_pre:.1f} s)")
    top = ax.get_xaxis_transform()
    ax.text(t_pre / 2, 0.985, "transfer", transform=top, ha="center", va="top", fontsize=8, color="0.35")
    ax.text((t_pre + t_end) / 2, 0.985, "insertion", transform=top, ha="center", va="top", fontsize=8, color="0.35")


def _t_pre(traj: pd.DataFrame) -> float | None:
    t = traj.t_s[traj.phase == "pre_insertion"]
    return float(t.iloc[0]) if len(t) else None


def _held(worst_m: float, worst_rad: float, tolerance: float) -> str:
    """The constraint errors' verdict: within the solver's tolerance (what decides), else at least the spec's 7e-7 m."""
    if max(worst_m, worst_rad) <= tolerance:
        margin = f"{SPEC_M / worst_m:.0f}× under" if worst_m > 0 else "under"
        return f"held at every node, within the solver's tolerance {tolerance:g} ({margin} the spec's 7e-7 m)"
    if worst_m <= SPEC_M:
        return f"ABOVE the solver's tolerance {tolerance:g}, within the spec's 7e-7 m"
    return f"NOT HELD: above the solver's tolerance {tolerance:g} and the spec's 7e-7 m"


def constraint_errors(traj: pd.DataFrame, out_png: str | Path, tolerance: float) -> None:
    """Closed-chain and path errors at the nodes (each the norm of its 3-vector; log scale, an exact zero drawn at
    1e-16) against the solver's ``tolerance`` (config ``dualarm.solver.tolerance``, m and rad: what decides), the
    position also against the spec's 7e-7 m; the verdict in the title."""
    fig, axes = plt.subplots(2, 1, figsize=(12, 7), sharex=True)
    rows = ((axes[0], "position", "m", ("closed_chain_pos_err_m", "path_err_m"), "path (panel on the pin axis, key poses)"),
            (axes[1], "rotation", "rad", ("closed_chain_rot_err_rad", "path_err_rad"),
             "path (vertical axis, orientation, key poses)"))
    worst = []
    for ax, what, unit, cols, path_label in rows:
        for col, label in zip(cols, ("closed chain (right gripper\nin the left gripper's frame)", path_label)):
            ax.semilogy(traj.t_s, np.maximum(traj[col], ZERO), lw=1.4, label=label)
        worst.append(max(float(traj[c].max()) for c in cols))
        ax.axhline(tolerance, color="tab:red", ls="--", lw=1.3, label=TOLERANCE.format(tolerance, unit))
        if unit == "m":
            ax.axhline(SPEC_M, color="0.35", ls="-.", lw=1.1, label=SPEC)
        ax.set(ylabel=f"{what} error at the node [{unit}]\n(norm over its components)",
               ylim=(ZERO / 5, 300 * max(tolerance, worst[-1], SPEC_M if unit == "m" else 0.0)))
        _phases(ax, _t_pre(traj), float(traj.t_s.iloc[-1]))
        ax.plot([], [], " ", label="(an exact zero is drawn at 1e-16)")
        ax.grid(alpha=0.3, which="major")
        legend_beside(ax)
    axes[-1].set_xlabel("time t [s]")
    fig.suptitle(f"Task constraints {_held(worst[0], worst[1], tolerance)}:\nlargest error {worst[0]:.1e} m, "
                 f"{worst[1]:.1e} rad (a norm per node; convergence.png plots the solver's measure, the largest single "
                 "component, hence slightly less)", fontsize=11)
    save(fig, out_png)


def distances(traj: pd.DataFrame, fine: pd.DataFrame, margin_m: float, active: list, tolerance: float,
              out_png: str | Path) -> None:
    """The smallest safety distance over all pairs of collision volumes on the finer grid (the executed motion),
    the margin and contact drawn, the pairs that come within 1 cm marked (``active``: name, distance, time, ...);
    below, zoomed to µm about the margin: the nodes (held to the solver's ``tolerance``, m) and the finer grid
    between them. The verdict in the title."""
    fig, (ax, zoom) = plt.subplots(2, 1, figsize=(12, 7.5), sharex=True, height_ratios=[2, 1.1])
    d_fine, margin = 1e3 * fine.min_distance_m, 1e3 * margin_m
    factor = round((len(fine) - 1) / max(len(traj) - 1, 1))
    ax.plot(fine.t_s, d_fine, color="tab:blue", lw=1.6, label=f"the executed motion ({factor}× finer\nthan the nodes)")
    ax.axhline(margin, color="tab:orange", ls="--", label=f"safety margin kept at the nodes ({margin:g} mm)")
    ax.axhline(0.0, color="tab:red", lw=1.2, label="contact (0 mm)")
    if active:
        ax.plot([], [], " ", label="pairs within 1 cm, at their closest:")
    for i, (name, d, tm, *_) in enumerate(sorted(active, key=lambda a: a[2])):
        ax.plot(tm, 1e3 * d, "osD^v<>"[i % 7], ms=10, mfc="none", mew=2, color=f"C{(i + 2) % 10}", zorder=3,
                label=f"{name}:\n{1e3 * d:.2f} mm at {tm:.2f} s")
    top = min(float(d_fine.max()), 200.0)
    ax.set(ylabel="smallest safety distance [mm]", ylim=(min(-1.0, d_fine.min() - 1), 1.15 * top + 3))
    _phases(ax, _t_pre(traj), float(fine.t_s.iloc[-1]))
    under_f, under_n = 1e6 * (fine.min_distance_m - margin_m), 1e6 * (traj.min_distance_m - margin_m)
    zoom.plot(fine.t_s, under_f, color="tab:blue", lw=1.2, label="between the nodes (finer grid)")
    zoom.plot(traj.t_s, under_n, ".", color="black", ms=3, label="at the nodes")
    zoom.axhline(0.0, color="tab:orange", ls="--", label="the margin")
    low = min(-1.0, 1.5 * float(under_f.min()))
    zoom.set(xlabel="time t [s]", ylabel=f"distance − the {margin:g} mm\nmargin [µm] (zoom)", ylim=(low, 4 * abs(low)))
    for a in (ax, zoom):
        a.grid(alpha=0.3)
        legend_beside(a)
    low_f, node_low, tol = float(d_fine.min()), float(traj.min_distance_m.min()), 1e3 * tolerance
    below = (f"between them down to {1e3 * (margin - low_f):.2f} µm under it" if low_f < margin - tol
             else "never under it between them")
    fig.suptitle(f"Smallest distance between any two collision volumes (arm capsules, panel, fitted scene) over time: "
                 f"{min(low_f, 1e3 * node_low):.3f} mm " + ("> 0: collision-free" if min(low_f, node_low) > 0 else
                                                             "≤ 0: IN COLLISION")
                 + f"\nthe {margin:g} mm margin {'held' if 1e3 * node_low >= margin - tol else 'NOT held'} at the nodes "
                 f"(to the solver's tolerance, {1e6 * tolerance:g} µm); " + below, fontsize=11)
    save(fig, out_png)


def joints(traj: pd.DataFrame, meta: dict, which: str, out_png: str | Path) -> None:
    """Each joint's position (which='q') as % of its range, or velocity (which='qd') as % of its limit,
    one panel per arm with the limits drawn (0 / 100 % of the range; the velocities, far below their limits,
    zoomed to the data, beside a full-scale gauge with the ±100 % limits and the band they fill); the joint that
    comes closest to a limit (positions: in rad; velocities: in % of its limit) is marked on its curve and named
    in the title with its margin (rad, rad/s)."""
    names, q = meta["joints"], which == "q"
    lo = np.asarray(meta["q_lower"]) if q else -np.asarray(meta["v_max"])
    hi = np.asarray(meta["q_upper"]) if q else np.asarray(meta["v_max"])
    unit, what, whats = ("rad", "position", "positions") if q else ("rad/s", "velocity", "velocities")
    t = traj.t_s.to_numpy()
    vals = np.column_stack([traj[f"{which}_{n}_{unit.replace('/', '_')}"].to_numpy() for n in names])
    pct = 100 * (vals - lo) / (hi - lo) if q else 100 * vals / hi
    margin = np.minimum(vals - lo, hi - vals)  # rad or rad/s to the nearer limit
    k, c = np.unravel_index(int(np.argmin(margin if q else margin / hi)), margin.shape)
    fig = plt.figure(figsize=(12, 8), layout="constrained")
    grid = fig.add_gridspec(2, 1) if q else fig.add_gridspec(2, 2, width_ratios=[0.6, 12])
    span = 1.3 * max(float(np.abs(pct).max()), 1.0)
    ylim, limits = ((-15, 115), (0, 100)) if q else ((-span, span), (-100, 100))
    off = "" if q or span > 100 else " (±100 %:\noff this zoomed scale)"
    axes = []
    for row, side in enumerate(("left", "right")):
        ax = fig.add_subplot(grid[row, -1], sharex=axes[0] if axes else None)
        mine = [j for j, n in enumerate(names) if n.startswith(side)]
        if not q:
            limit_gauge(fig.add_subplot(grid[row, 0]), pct[:, mine])
        for i, j in enumerate(mine):
            peak = f": peak {np.abs(pct[:, j]).max():.1f} %" if not q else ""
            ax.plot(t, pct[:, j], lw=2.2 if j == c else 1.3, color=f"C{i}", label=names[j] + peak,
                    zorder=3 if j == c else on_top(pct[:, mine], i))
        for y in limits:
            ax.axhline(y, color="tab:red", ls="--", lw=1.2, label="joint limit" + off if y == limits[1] else None)
        if c in mine:
            ax.plot(t[k], pct[k, c], "o", ms=11, mfc="none", mec="black", mew=2, zorder=4, label="closest to a limit")
            ax.annotate(names[c], (t[k], pct[k, c]), xytext=(8, -14 if pct[k, c] < 0 else 8),
                        textcoords="offset points", fontsize=8.5, fontweight="bold")
        lim_txt = "% of its range: 0 = lower, 100 = upper limit" if q else "% of its limit (zoomed: limits ±100 %)"
        ax.set(ylim=ylim, ylabel=f"{side} arm: {what}\n[{lim_txt}]")
        _phases(ax, _t_pre(traj), float(t[-1]))
        ax.grid(alpha=0.3)
        legend_beside(ax)
        axes.append(ax)
    axes[0].tick_params(labelbottom=False)
    axes[-1].set_xlabel("time t [s]")
    side = "lower" if vals[k, c] - lo[c] <= hi[c] - vals[k, c] else "upper"
    closest = (f"closest: {names[c]}, {margin[k, c]:.3f} {unit} from its {side} limit at t = {t[k]:.1f} s" if q else
               f"closest: {names[c]}, {abs(pct[k, c]):.1f} % of its limit ({abs(vals[k, c]):.3f} of {hi[c]:g} rad/s, "
               f"{margin[k, c]:.3f} rad/s to spare) at t = {t[k]:.1f} s")
    limits_txt = "" if q else f" (limits {', '.join(f'{v:g}' for v in sorted(set(np.round(hi, 6))))} rad/s)"
    fig.suptitle(f"Joint {whats} of both arms: {'all within their limits' if (margin >= 0).all() else 'a LIMIT IS EXCEEDED'}"
                 f"{limits_txt}\n{closest}", fontsize=11)
    save(fig, out_png)


def torques(tq: pd.DataFrame, meta: dict, t_pre: float, out_png: str | Path) -> None:
    """Each joint's |torque| in % of its effort limit with the least-norm internal force between the grippers (the
    torques the verdict is on), per arm, the limit drawn; black dotted: the arm's peak with the best internal force
    (the least any internal force allows). ``meta``: the torques' provenance (joints, effort_nm, panel_kg)."""
    names, effort, panel_kg = meta["joints"], np.asarray(meta["effort_nm"]), meta["panel_kg"]
    ratio = np.column_stack([100 * tq[f"tau_{n}_nm"].abs().to_numpy() / effort[c] for c, n in enumerate(names)])
    best = np.column_stack([100 * tq[f"tau_best_{n}_nm"].abs().to_numpy() / effort[c] for c, n in enumerate(names)])
    fig, axes = plt.subplots(2, 1, figsize=(12, 8), sharex=True)
    for side, ax in zip(("left", "right"), axes):
        mine = [c for c, n in enumerate(names) if n.startswith(side)]
        for i, c in enumerate(mine):
            ax.plot(tq.t_s, ratio[:, c], lw=1.4, color=f"C{i}", zorder=on_top(ratio[:, mine], i),
                    label=f"{names[c]}: peak {ratio[:, c].max():.2g} % (limit {effort[c]:g} N·m)")
        ax.plot(tq.t_s, best[:, mine].max(axis=1), color="black", ls=":", lw=1.6,
                label="with the best internal force:\nthis arm's largest joint")
        ax.axhline(100, color="tab:red", lw=1.2, ls="--", label="effort limit (100 %)")
        ax.set(ylabel=f"{side} arm: |torque|\n[% of the joint's effort limit]", ylim=(-4, 115))
        _phases(ax, t_pre, float(tq.t_s.iloc[-1]))
        ax.grid(alpha=0.3)
        legend_beside(ax)
    axes[-1].set_xlabel("time t [s]")
    k, c = np.unravel_index(int(ratio.argmax()), ratio.shape)
    verdict = "EXCEEDS the effort limit" if ratio.max() > 100 else "within the effort limits"
    fig.suptitle(f"Joint torques holding the {panel_kg:g} kg panel: {verdict}, peak {ratio.max():.0f} % ({names[c]} at "
                 f"{tq.t_s.iloc[k]:.1f} s)\ninverse dynamics; coloured: with the least-norm internal force between "
                 f"the grippers, the case judged here and in summary.csv;\ndotted: the best internal force (a "
                 f"torque-sharing controller, not part of this run) would bring the peak to {best.max():.0f} %",
                 fontsize=11)
    save(fig, out_png)


def convergence(outer: pd.DataFrame, out_png: str | Path, tolerance: float | None = None,
                node_errors: tuple[float, float] | None = None) -> None:
    """Per outer iteration of the augmented-Lagrangian loop: the constraint violations (the largest residual
    component at any node, each in its SI unit: m, rad or rad/s) against the loop's ``tolerance`` (it stops below
    it), with the result's largest node errors (``node_errors``: m, rad, the norms of constraint_errors.png), and,
    on its own axis, the penalty μ (dimensionless weight); the verdict in the title."""
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(11, 6.8), sharex=True, height_ratios=[2, 1])
    ax.semilogy(outer.outer, outer.eq_violation, "o-", label="equalities (closed chain, path,\nkey poses, final rest)")
    ax.semilogy(outer.outer, np.maximum(outer.in_violation, ZERO), "s-",
                label="inequalities (distances − margin,\njoint position and velocity limits)")
    last = max(float(outer.eq_violation.iloc[-1]), float(outer.in_violation.iloc[-1]))
    if tolerance is not None:
        ax.axhline(tolerance, color="tab:red", ls="--", lw=1.2, label=TOLERANCE.format(tolerance, "") + ":\nit stops below")
    if node_errors is not None:
        n = outer.outer.iloc[-1] + 0.4  # beside the last iteration's residuals
        ax.plot([n, n], node_errors, "D", ms=8, mfc="none", mew=1.6, color="tab:green", zorder=3,
                label=f"the result's largest node errors:\n{node_errors[0]:.1e} m, {node_errors[1]:.1e} rad "
                      "(norms of 3-vectors,\nconstraint_errors.png)")
    ax.set(ylabel="largest residual component at any node\n[its SI unit: m, rad or rad/s]")
    ax.grid(alpha=0.3)
    legend_beside(ax)
    ax2.semilogy(outer.outer, outer.mu, "^--", color="0.3")
    ax2.set(xlabel="outer iteration", ylabel="penalty μ\n[dimensionless]")
    ax2.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
    ax2.grid(alpha=0.3)
    done = "converged" if tolerance is None or last <= tolerance else "NOT converged"
    bound = "" if tolerance is None else f" {'≤' if last <= tolerance else '>'} tolerance {tolerance:g}"
    fig.suptitle(f"Augmented Lagrangian {done}: {len(outer)} outer iterations around {int(outer.inner_iterations.sum())}"
                 " inner ones of FDDP (Crocoddyl's feasibility-driven DDP)\n"
                 f"largest residual component at the end {last:.1e}{bound}", fontsize=11)
    save(fig, out_png)


@dataclass(frozen=True, eq=False)
class Surroundings:
    """The static environment the arms move in: swept triangles ``tri`` (T, 3, 3) m (their cores) and capsules
    ``seg`` (a (3,) m, b (3,) m, radius m) each; ``tri_label`` (T,): the solid each triangle was fitted to
    (empty: unknown; the enclosure's walls are then told from the obstacles by their extent)."""

    tri: np.ndarray
    seg: list[tuple[np.ndarray, np.ndarray, float]]
    tri_label: np.ndarray = field(default_factory=lambda: np.array([], dtype=object))


@dataclass(frozen=True, eq=False)
class Held:
    """The held panel and where it goes: the body (index) it is fixed to and its pose there (4, 4); its size (3,) m along
    its x (thickness), y, z; its holes (h, 2) panel-local (y, z) m of radius ``hole_r`` m; its final pose (4, 4) in the
    world (None: not drawn); the pins it slides onto, the scene's solids (a (3,) m, b (3,) m, radius m)."""

    body: int
    in_body: np.ndarray
    size: np.ndarray
    holes: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    hole_r: float = 0.0
    final: np.ndarray | None = None
    pins: tuple = ()


ROBOT, STATIC, PANEL, PIN, HOLE = 0x4070B0, 0x8090A0, 0xD0A030, 0xC02020, 0x202020  # the robot, the panel, the pins
OBSTACLE, WALL, ROD = 0x3C9A50, 0x9AB0A0, 0xA07050  # the fitted envelope
EYE = np.array([0.75, -0.85, 0.35])  # the camera from the insertion's centre, m: in front, right, above: no arm in the way


def _walls(env: Surroundings) -> np.ndarray:
    """Which triangles belong to the enclosure: their solid spans at least 90 % of the whole environment's
    extent along two axes (a wall, the floor, the ceiling), the rest being the obstacles in the cabin."""
    labels = _labels(env)
    span = np.ptp(env.tri.reshape(-1, 3), axis=0) if len(env.tri) else np.ones(3)
    wall = {lab: (np.ptp(env.tri[labels == lab].reshape(-1, 3), axis=0) >= 0.9 * span).sum() >= 2
            for lab in np.unique(labels)}
    return np.array([wall[lab] for lab in labels], dtype=bool)


def _labels(env: Surroundings) -> np.ndarray:
    """The solid of each triangle (its index when the envelope has no labels)."""
    return env.tri_label if len(env.tri_label) == len(env.tri) else np.arange(len(env.tri)).astype(str)


def _panel(node, held: Held, look, holes: bool) -> None:
    """The panel's board under ``node`` (its frame) and its holes (dark discs through it); without them, its outline."""
    node["board"].set_object(g.Box(list(held.size)), look)
    t, w, h = np.asarray(held.size, float) / 2
    pieces = ([(np.array([-t - 0.001, y, z]), np.array([t + 0.001, y, z]), held.hole_r) for y, z in held.holes] if holes
              else [(np.array([0, *a]), np.array([0, *b]), 0.002) for a, b in zip([(-w, -h), (w, -h), (w, h), (-w, h)],
                                                                                  [(w, -h), (w, h), (-w, h), (-w, -h)])])
    for k, (a, b, r) in enumerate(pieces):
        geom, pose = cylinder(a, b, r)
        node[f"edge{k}"].set_object(geom, material(HOLE if holes else PANEL))
        node[f"edge{k}"].set_transform(pose)


def _legend(env: Surroundings, walls: np.ndarray, held: Held) -> tuple:
    solids = ", ".join(sorted({str(lab).replace("_", " ") for lab in _labels(env)[~walls]}))
    return ((ROBOT, 1.0, "Baxter's arms: capsules over their geometry"),
            (STATIC, 0.18, "torso, head, pedestal (static)"),
            (PANEL, 1.0, "the panel (its holes dark), held by both grippers"),
            (PANEL, 0.25, "the panel's final pose on the pins (outlined)"),
            (PIN, 1.0, f"the {len(held.pins)} pins (the scene's solids)"),
            (ROD, 0.3, "fitted capsules: pins, strut, block edges"),
            (OBSTACLE, 0.22, f"fitted envelope: {solids} (triangle cores)"),
            (WALL, 0.12, "fitted envelope: the cabin (walls facing the camera cut away)"))


def animation(capsules: list[tuple[str, int, np.ndarray, np.ndarray, float]], poses: np.ndarray, held: Held,
              env: Surroundings, fps: float, caption: Overlay, out_html: str | Path) -> None:
    """MeshCat static HTML: capsules (name, body index, a, b in the body frame, r) moved by body poses
    (F, B, 4, 4), sampled at ``fps`` from t = 0; the ``held`` panel with its holes, its final pose (translucent)
    and the pins; the environment's swept triangles (their cores, translucent: the enclosure faint, its walls
    facing the camera cut away) and capsules (static). The camera looks at the insertion (the panel's path and
    the pins). Over the view: the ``caption`` (title, lines, one text per frame), a legend of the colours and the
    simulated time (looped)."""
    panel_at = np.einsum("fij,jk->fik", poses[:, held.body], held.in_body)[:, :3, 3]
    ends = np.vstack([panel_at, *[np.vstack([a, b]) for a, b, _ in held.pins]])
    centre = (ends.min(axis=0) + ends.max(axis=0)) / 2
    walls = _walls(env)
    vis = new_scene(replace(caption, legend=_legend(env, walls, held), fps=fps))
    for name, body, a, b, r in capsules:
        capsule(vis[f"robot/body{body}/{name}"], a, b, r, material(ROBOT) if body else material(STATIC, 0.18))
    vis[f"robot/body{held.body}/panel"].set_transform(held.in_body)
    _panel(vis[f"robot/body{held.body}/panel"], held, material(PANEL), holes=True)
    if held.final is not None:
        _panel(vis["environment/final_pose"], held, material(PANEL, 0.25), holes=False)
        vis["environment/final_pose"].set_transform(held.final)
    for k, (a, b, r) in enumerate(held.pins):
        geom, pose = cylinder(a, b, r)
        vis[f"environment/pin{k}"].set_object(geom, material(PIN))
        vis[f"environment/pin{k}"].set_transform(pose)
    cut = facing(env.tri, _labels(env), centre, EYE)
    for part, keep, look in (("obstacles", ~walls, material(OBSTACLE, 0.22)), ("walls", walls & ~cut, material(WALL, 0.12))):
        if keep.any():
            tri = env.tri[keep].reshape(-1, 3)
            vis[f"environment/{part}"].set_object(g.TriangularMeshGeometry(tri, np.arange(len(tri)).reshape(-1, 3)), look)
    for k, (a, b, r) in enumerate(env.seg):
        capsule(vis[f"environment/capsule{k}"], a, b, r, material(ROD, 0.3))
    anim = ma.Animation(default_framerate=fps)
    for f, frame in enumerate(poses):
        with anim.at_frame(vis, f) as fv:
            for b, T in enumerate(frame):
                fv[f"robot/body{b}"].set_transform(T)
    for b, T in enumerate(poses[0]):
        vis[f"robot/body{b}"].set_transform(T)
    vis.set_animation(anim, play=True, repetitions=2**31 - 1)  # looped until the page is closed
    hide_helpers(vis)  # the cabin's floor is the ground
    aim(vis, ("robot", "environment"), centre, EYE, right=0.12)
    write_html(vis, out_html)
