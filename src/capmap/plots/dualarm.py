"""Figures of the dual-arm assembly: task-constraint errors, safety distances, joints and their
velocities against the limits, the joint torques with the held panel against the effort limits, the
solver's convergence, and the 3D animation."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import meshcat.animation as ma
import numpy as np
import pandas as pd

from capmap.plots.common import legend_beside, plt, save
from capmap.plots.scene3d import Overlay, aim, cylinder, g, material, new_scene, write_html

__all__ = ["constraint_errors", "distances", "joints", "torques", "convergence", "Surroundings", "animation"]

REQUIRED_M = 7e-7  # the paper's reported maximum closed-chain / path error
REFERENCE_RAD = 1e-6  # the rotation errors' reference
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


def constraint_errors(traj: pd.DataFrame, out_png: str | Path) -> None:
    """Closed-chain and path errors at the nodes (log scale; an exact zero drawn at 1e-16), against the
    paper's 7e-7 m and 1e-6 rad; the verdict in the title."""
    fig, axes = plt.subplots(2, 1, figsize=(12, 7), sharex=True)
    rows = ((axes[0], "position", "m", REQUIRED_M, "7e-7 m: the paper's maximum",
             ("closed_chain_pos_err_m", "path_err_m"), "path (panel on the pin axis, key poses)"),
            (axes[1], "rotation", "rad", REFERENCE_RAD, "1e-6 rad: reference",
             ("closed_chain_rot_err_rad", "path_err_rad"), "path (vertical axis, orientation, key poses)"))
    worst = []
    for ax, what, unit, ref, ref_label, cols, path_label in rows:
        for col, label in zip(cols, ("closed chain (right gripper in the left gripper's frame)", path_label)):
            ax.semilogy(traj.t_s, np.maximum(traj[col], ZERO), lw=1.4, label=label)
        worst.append(max(float(traj[c].max()) for c in cols))
        ax.axhline(ref, color="tab:red", ls="--", lw=1.2, label=ref_label)
        ax.set(ylabel=f"{what} error [{unit}]", ylim=(ZERO / 5, 100 * max(ref, worst[-1])))
        _phases(ax, _t_pre(traj), float(traj.t_s.iloc[-1]))
        ax.plot([], [], " ", label="(an exact zero is drawn at 1e-16)")
        ax.grid(alpha=0.3, which="major")
        legend_beside(ax)
    axes[-1].set_xlabel("time t [s]")
    ok = worst[0] <= REQUIRED_M and worst[1] <= REFERENCE_RAD
    fig.suptitle(f"Task constraints at the nodes: largest error {worst[0]:.1e} m {'≤' if worst[0] <= REQUIRED_M else '>'} 7e-7 m"
                 f", {worst[1]:.1e} rad {'≤' if worst[1] <= REFERENCE_RAD else '>'} 1e-6 rad: "
                 + ("the closed chain and the path are held" if ok else "NOT within the paper's accuracy"), fontsize=11)
    save(fig, out_png)


def distances(traj: pd.DataFrame, fine: pd.DataFrame, margin_m: float, active: list, out_png: str | Path) -> None:
    """The smallest safety distance over all pairs at the nodes and on the finer grid, the margin and contact
    drawn, the pairs that come within 1 cm marked (``active``: name, distance, time, ...); the verdict in the title."""
    fig, ax = plt.subplots(figsize=(12, 5))
    d_fine, d_node, margin = 1e3 * fine.min_distance_m, 1e3 * traj.min_distance_m, 1e3 * margin_m
    ax.plot(fine.t_s, d_fine, color="tab:blue", lw=3, alpha=0.5, label="finer grid (between the nodes too)")
    ax.plot(traj.t_s, d_node, ".", color="black", ms=2, label="at the nodes")
    ax.axhline(margin, color="tab:orange", ls="--", label=f"safety margin kept at the nodes ({margin:g} mm)")
    ax.axhline(0.0, color="tab:red", lw=1.2, label="contact (0 mm)")
    if active:
        ax.plot([], [], " ", label="pairs within 1 cm, at their closest:")
    for i, (name, d, tm, *_) in enumerate(sorted(active, key=lambda a: a[2])):
        ax.plot(tm, 1e3 * d, "osD^v<>"[i % 7], ms=10, mfc="none", mew=2, color=f"C{(i + 2) % 10}",
                label=f"{name}: {1e3 * d:.2f} mm at {tm:.2f} s")
    top = min(float(d_fine.max()), 200.0)
    ax.set(xlabel="time t [s]", ylabel="smallest safety distance [mm]", ylim=(min(-1.0, d_fine.min() - 1), 1.15 * top + 3))
    _phases(ax, _t_pre(traj), float(fine.t_s.iloc[-1]))
    ax.grid(alpha=0.3)
    legend_beside(ax)
    low, node_low = float(min(d_fine.min(), d_node.min())), float(d_node.min())
    tol = 1e-4  # mm (0.1 µm): the solver's tolerance on the margin
    below = (f"on the finer grid down to {d_fine.min():.4f} mm ({1e3 * (margin - d_fine.min()):.2f} µm under the margin)"
             if d_fine.min() < margin - tol else "never under the margin on the finer grid")
    fig.suptitle(f"Closest pair of swept volumes: smallest safety distance {low:.3f} mm "
                 + ("> 0 mm: collision-free" if low > 0 else "≤ 0 mm: IN COLLISION")
                 + f"\nat the nodes {node_low:.3f} mm {'≥' if node_low >= margin - tol else '<'} {margin:g} mm margin; "
                 + below, fontsize=11)
    save(fig, out_png)


def joints(traj: pd.DataFrame, meta: dict, which: str, out_png: str | Path) -> None:
    """Each joint's position (which='q') as % of its range, or velocity (which='qd') as % of its limit,
    one panel per arm with the limits drawn (0 / 100 % of the range, ±100 % of the velocity limit); the
    joint that comes closest to a limit is marked and named with its margin (rad, rad/s) in the title."""
    names = meta["joints"]
    lo = np.asarray(meta["q_lower"]) if which == "q" else -np.asarray(meta["v_max"])
    hi = np.asarray(meta["q_upper"]) if which == "q" else np.asarray(meta["v_max"])
    unit, what, whats = ("rad", "position", "positions") if which == "q" else ("rad/s", "velocity", "velocities")
    t = traj.t_s.to_numpy()
    vals = np.column_stack([traj[f"{which}_{n}_{unit.replace('/', '_')}"].to_numpy() for n in names])
    pct = 100 * (vals - lo) / (hi - lo) if which == "q" else 100 * vals / hi
    margin = np.minimum(vals - lo, hi - vals)  # rad or rad/s to the nearer limit
    k, c = np.unravel_index(int(np.argmin(margin)), margin.shape)
    fig, axes = plt.subplots(2, 1, figsize=(12, 8), sharex=True)
    limits = (0, 100) if which == "q" else (-100, 100)
    for side, ax in zip(("left", "right"), axes):
        for j in (j for j, n in enumerate(names) if n.startswith(side)):
            ax.plot(t, pct[:, j], lw=1.3, label=names[j])
        for y in limits:
            ax.axhline(y, color="tab:red", ls="--", lw=1.2, label="joint limit" if y == limits[1] else None)
        if names[c].startswith(side):
            ax.plot(t[k], pct[k, c], "o", ms=11, mfc="none", mec="black", mew=2, label="closest to a limit")
        lim_txt = "% of its range: 0 = lower, 100 = upper limit" if which == "q" else "% of its limit"
        ax.set(ylim=(limits[0] - 15, 115), ylabel=f"{side} arm: {what}\n[{lim_txt}]")
        _phases(ax, _t_pre(traj), float(t[-1]))
        ax.grid(alpha=0.3)
        legend_beside(ax)
    axes[-1].set_xlabel("time t [s]")
    side = "lower" if vals[k, c] - lo[c] <= hi[c] - vals[k, c] else "upper"
    inside = bool((margin >= 0).all())
    peak = f"peak {np.abs(pct).max():.0f} % of the limit; " if which == "qd" else ""
    fig.suptitle(f"Joint {whats} of both arms: {'all within their limits' if inside else 'a LIMIT IS EXCEEDED'}\n"
                 f"{peak}closest: {names[c]}, {margin[k, c]:.3f} {unit} from its {side} limit at t = {t[k]:.1f} s",
                 fontsize=11)
    save(fig, out_png)


def torques(tq: pd.DataFrame, meta: dict, t_pre: float, out_png: str | Path) -> None:
    """Each joint's torque (least-norm internal force) in % of its effort limit, per arm, the limits
    drawn; the peak with the best internal force and the verdict in the title. ``meta``: the torques'
    provenance (joints, effort_nm, panel_kg)."""
    names, effort, panel_kg = meta["joints"], np.asarray(meta["effort_nm"]), meta["panel_kg"]
    fig, axes = plt.subplots(2, 1, figsize=(12, 8), sharex=True)
    peak_best = 0.0
    for side, ax in zip(("left", "right"), axes):
        for c in (c for c, n in enumerate(names) if n.startswith(side)):
            ax.plot(tq.t_s, 100 * tq[f"tau_{names[c]}_nm"] / effort[c], lw=1.3, label=f"{names[c]} (limit {effort[c]:g} N·m)")
            peak_best = max(peak_best, float((100 * tq[f"tau_best_{names[c]}_nm"].abs() / effort[c]).max()))
        for y in (-100, 100):
            ax.axhline(y, color="tab:red", lw=1.2, ls="--", label="effort limit (±100 %)" if y > 0 else None)
        ax.set(ylabel=f"{side} arm: torque\n[% of the joint's effort limit]", ylim=(-115, 115))
        _phases(ax, t_pre, float(tq.t_s.iloc[-1]))
        ax.grid(alpha=0.3)
        legend_beside(ax)
    axes[-1].set_xlabel("time t [s]")
    ratio = np.array([100 * tq[f"tau_{n}_nm"].abs().to_numpy() / effort[c] for c, n in enumerate(names)])
    c, k = np.unravel_index(int(ratio.argmax()), ratio.shape)
    verdict = "EXCEEDS the effort limit" if ratio.max() > 100 else "within the effort limits"
    fig.suptitle(f"Joint torques holding the {panel_kg:g} kg panel: peak {ratio.max():.0f} % ({names[c]} at "
                 f"{tq.t_s.iloc[k]:.1f} s), {verdict}\ninverse dynamics with the least-norm internal force between the "
                 f"grippers; the best internal force brings the peak to {peak_best:.0f} %", fontsize=11)
    save(fig, out_png)


def convergence(outer: pd.DataFrame, out_png: str | Path, tolerance: float | None = None) -> None:
    """Per outer iteration of the augmented-Lagrangian loop: the constraint violations (m or rad, the
    largest residual of either kind) against the loop's ``tolerance`` (m or rad: it stops below it) and, on
    its own axis, the penalty μ (dimensionless weight); the verdict in the title."""
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, height_ratios=[2, 1])
    ax.semilogy(outer.outer, outer.eq_violation, "o-", label="equality (closed chain, path)")
    ax.semilogy(outer.outer, np.maximum(outer.in_violation, ZERO), "s-", label="inequality (distances, limits)")
    last = max(float(outer.eq_violation.iloc[-1]), float(outer.in_violation.iloc[-1]))
    if tolerance is not None:
        ax.axhline(tolerance, color="tab:red", ls="--", lw=1.2, label=f"tolerance {tolerance:g} (stops below it)")
    ax.set(ylabel="largest violation [m or rad]")
    ax.grid(alpha=0.3)
    legend_beside(ax)
    ax2.semilogy(outer.outer, outer.mu, "^--", color="0.3")
    ax2.set(xlabel="outer iteration", ylabel="penalty μ\n[dimensionless]")
    ax2.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
    ax2.grid(alpha=0.3)
    done = "converged" if tolerance is None or last <= tolerance else "NOT converged"
    bound = "" if tolerance is None else f" {'≤' if last <= tolerance else '>'} tolerance {tolerance:g}"
    fig.suptitle(f"Augmented Lagrangian {done}: {len(outer)} outer, {int(outer.inner_iterations.sum())} FDDP "
                 f"iterations\nlargest violation at the end {last:.1e}{bound}", fontsize=11)
    save(fig, out_png)


@dataclass(frozen=True, eq=False)
class Surroundings:
    """The static environment the arms move in: swept triangles ``tri`` (T, 3, 3) m (their cores) and capsules
    ``seg`` (a (3,) m, b (3,) m, radius m) each; ``tri_label`` (T,): the solid each triangle was fitted to
    (empty: unknown; the enclosure's walls are then told from the obstacles by their extent)."""

    tri: np.ndarray
    seg: list[tuple[np.ndarray, np.ndarray, float]]
    tri_label: np.ndarray = field(default_factory=lambda: np.array([], dtype=object))


ROBOT, STATIC, PANEL, OBSTACLE, WALL, ROD = 0x4070B0, 0x8090A0, 0xD0A030, 0x3C9A50, 0x9AB0A0, 0xA07050


def _walls(env: Surroundings) -> np.ndarray:
    """Which triangles belong to the enclosure: their solid spans at least 90 % of the whole environment's
    extent along two axes (a wall, the floor, the ceiling), the rest being the obstacles in the cabin."""
    labels = env.tri_label if len(env.tri_label) == len(env.tri) else np.arange(len(env.tri)).astype(str)
    pts = env.tri.reshape(-1, 3)
    span = np.ptp(pts, axis=0) if len(pts) else np.ones(3)
    wall = {lab: (np.ptp(env.tri[labels == lab].reshape(-1, 3), axis=0) >= 0.9 * span).sum() >= 2
            for lab in np.unique(labels)}
    return np.array([wall[lab] for lab in labels], dtype=bool)


def animation(capsules: list[tuple[str, int, np.ndarray, np.ndarray, float]], poses: np.ndarray, panel: tuple,
              env: Surroundings, fps: float, caption: Overlay, out_html: str | Path) -> None:
    """MeshCat static HTML: capsules (name, body index, a, b in the body frame, r) moved by body poses
    (F, B, 4, 4), sampled at ``fps`` from t = 0; the panel (body index, pose in that body, size); the environment's
    swept triangles (their cores, translucent: the enclosure faint) and capsules (static). Over the view: the
    ``caption`` (title, lines, one text per frame), a legend of the colours and the simulated time (looped)."""
    walls = _walls(env)
    legend = ((ROBOT, 1.0, "Baxter's arms: capsules over their geometry"),
              (STATIC, 0.3, "torso, head, pedestal (static)"), (PANEL, 1.0, "the panel, held by both grippers"),
              (OBSTACLE, 0.45, "fitted envelope: satellite, bulkhead, mounting block (triangle cores)"),
              (WALL, 0.12, "fitted envelope: the cabin's walls, floor, ceiling"),
              (ROD, 0.7, "fitted capsules: strut, pins"))
    vis = new_scene(replace(caption, legend=legend, fps=fps))
    for name, body, a, b, r in capsules:
        geom, pose = cylinder(a, b, r)
        node = vis[f"robot/body{body}/{name}"]
        look = material(ROBOT) if body else material(STATIC, 0.3)  # the static body translucent
        node["core"].set_object(geom, look)
        node["core"].set_transform(pose)
        for k, end in enumerate((a, b)):
            node[f"cap{k}"].set_object(g.Sphere(float(r)), look)
            T = np.eye(4)
            T[:3, 3] = end
            node[f"cap{k}"].set_transform(T)
    body, in_body, size = panel
    vis[f"robot/body{body}/panel"].set_object(g.Box(list(size)), material(PANEL))
    vis[f"robot/body{body}/panel"].set_transform(in_body)
    for part, keep, look in (("obstacles", ~walls, material(OBSTACLE, 0.45)), ("walls", walls, material(WALL, 0.12))):
        if keep.any():
            tri = env.tri[keep].reshape(-1, 3)
            vis[f"environment/{part}"].set_object(g.TriangularMeshGeometry(tri, np.arange(len(tri)).reshape(-1, 3)), look)
    for k, (a, b, r) in enumerate(env.seg):
        geom, pose = cylinder(a, b, r)
        vis[f"environment/capsule{k}"].set_object(geom, material(ROD, 0.7))
        vis[f"environment/capsule{k}"].set_transform(pose)
    anim = ma.Animation(default_framerate=fps)
    for f, frame in enumerate(poses):
        with anim.at_frame(vis, f) as fv:
            for b, T in enumerate(frame):
                fv[f"robot/body{b}"].set_transform(T)
    for b, T in enumerate(poses[0]):
        vis[f"robot/body{b}"].set_transform(T)
    vis.set_animation(anim, play=True, repetitions=2**31 - 1)  # looped until the page is closed
    vis["/Grid"].set_property("visible", False)  # the cabin's floor is the ground here
    moving = poses[:, 1:, :3, 3].reshape(-1, 3)  # the arms' joints, any time
    # front right, a little above the bulkhead: the arms, the panel and the pins in view
    aim(vis, ("robot", "environment"), (moving.min(axis=0) + moving.max(axis=0)) / 2, [1.4, -1.55, 0.75])
    write_html(vis, out_html)
