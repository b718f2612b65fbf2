"""Figures of the dual-arm assembly: task-constraint errors, safety distances, joints and their
velocities against the limits, the joint torques with the held panel against the effort limits, the
solver's convergence, and the 3D animation."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import meshcat.animation as ma
import numpy as np
import pandas as pd

from capmap.plots.common import plt, save
from capmap.plots.scene3d import cylinder, g, material, new_scene, write_html

__all__ = ["constraint_errors", "distances", "joints", "torques", "convergence", "Surroundings", "animation"]

REQUIRED_M = 7e-7  # the paper's reported maximum closed-chain / path error


def constraint_errors(traj: pd.DataFrame, out_png: str | Path) -> None:
    """Closed-chain and path errors at the nodes (log scale), with the 7e-7 m reference."""
    fig, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    floor = 1e-16
    axes[0].semilogy(traj.t_s, np.maximum(traj.closed_chain_pos_err_m, floor), label="closed chain (gripper to gripper)")
    axes[0].semilogy(traj.t_s, np.maximum(traj.path_err_m, floor), label="path (panel on the pin axis, poses)")
    axes[0].axhline(REQUIRED_M, color="tab:red", ls=":", label="7e-7 m (paper's maximum)")
    axes[0].set(ylabel="position error [m]", title="Task constraints at the nodes (zero shown at 1e-16)")
    axes[1].semilogy(traj.t_s, np.maximum(traj.closed_chain_rot_err_rad, floor), label="closed chain")
    axes[1].semilogy(traj.t_s, np.maximum(traj.path_err_rad, floor), label="path (vertical axis, orientation, poses)")
    axes[1].axhline(1e-6, color="tab:red", ls=":", label="1e-6 rad")
    axes[1].set(ylabel="rotation error [rad]", xlabel="t [s]")
    t_pre = traj.t_s[traj.phase == "pre_insertion"]
    for ax in axes:
        for tp in t_pre:
            ax.axvline(tp, color="0.5", lw=0.8, ls="--")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="upper left")
    axes[0].text(float(t_pre.iloc[0]) if len(t_pre) else 0, axes[0].get_ylim()[1], " pre-insertion", va="top", fontsize=8)
    save(fig, out_png)


def distances(traj: pd.DataFrame, fine: pd.DataFrame, margin_m: float, active: list, out_png: str | Path) -> None:
    """The smallest safety distance over all pairs: at the nodes and on the finer grid."""
    fig, ax = plt.subplots(figsize=(10, 4.8))
    ax.plot(fine.t_s, 1e3 * fine.min_distance_m, color="tab:blue", lw=3, alpha=0.5,
            label="finer grid (between nodes too)")
    ax.plot(traj.t_s, 1e3 * traj.min_distance_m, ".", color="black", ms=1.5, label="nodes")
    ax.axhline(1e3 * margin_m, color="tab:orange", ls="--", label=f"margin kept at the nodes ({1e3 * margin_m:g} mm)")
    ax.axhline(0.0, color="tab:red", lw=1, label="contact")
    for i, (name, d, tm, *_) in enumerate(sorted(active[:3], key=lambda a: a[2])):
        left = tm > 0.6 * fine.t_s.iloc[-1]  # keep the label inside the axes; stagger them in height
        ax.annotate(f"{name}\n{1e3 * d:.1f} mm", (tm, 1e3 * d), xytext=(-20 if left else 20, 28 + 30 * i),
                    textcoords="offset points", fontsize=8, ha="right" if left else "left",
                    arrowprops={"arrowstyle": "->", "lw": 0.6}, bbox={"fc": "white", "ec": "none", "alpha": 0.8})
    ax.set(xlabel="t [s]", ylabel="smallest safety distance [mm]",
           title="Closest pair of swept volumes (cores' distance minus radii) over the motion",
           ylim=(min(-1.0, 1e3 * fine.min_distance_m.min() - 1), 1e3 * min(fine.min_distance_m.max(), 0.2) + 5))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, out_png)


def joints(traj: pd.DataFrame, meta: dict, which: str, out_png: str | Path) -> None:
    """Each joint's position (which='q') as % of its range, or velocity (which='qd') as % of its limit,
    one panel per arm with the limits drawn (0 / 100 % of the range, ±100 % of the velocity limit); the
    joint that comes closest to a limit is marked there and named with its margin (rad, rad/s)."""
    names = meta["joints"]
    lo = np.asarray(meta["q_lower"]) if which == "q" else -np.asarray(meta["v_max"])
    hi = np.asarray(meta["q_upper"]) if which == "q" else np.asarray(meta["v_max"])
    unit = "rad" if which == "q" else "rad_s"
    t = traj.t_s.to_numpy()
    vals = np.column_stack([traj[f"{which}_{n}_{unit}"].to_numpy() for n in names])
    pct = 100 * (vals - lo) / (hi - lo) if which == "q" else 100 * vals / hi
    margin = np.minimum(vals - lo, hi - vals)  # rad or rad/s to the nearer limit
    k, c = np.unravel_index(int(np.argmin(margin)), margin.shape)
    fig, axes = plt.subplots(2, 1, figsize=(11, 8), sharex=True)
    for side, ax in zip(("left", "right"), axes):
        for j in (j for j, n in enumerate(names) if n.startswith(side)):
            ax.plot(t, pct[:, j], lw=1.3, label=names[j])
        if names[c].startswith(side):
            ax.plot(t[k], pct[k, c], "o", ms=10, mfc="none", mec="tab:red", mew=2,
                    label=f"closest to a limit: {names[c]}")
        if which == "q":
            for y in (0, 100):
                ax.axhline(y, color="tab:red", ls=":", lw=1.2)
            ax.set(ylim=(-8, 108), ylabel=f"{side} arm: position [% of its range]")
        else:
            top = max(1.3 * np.abs(pct).max(), 5.0)
            if top >= 100:
                for y in (-100, 100):
                    ax.axhline(y, color="tab:red", ls=":", lw=1.2)
            ax.set(ylim=(-min(top, 110), min(top, 110)), ylabel=f"{side} arm: velocity [% of its limit]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=4, loc="upper right")
    axes[-1].set_xlabel("time t [s]")
    unit_txt = "rad" if which == "q" else "rad/s"
    what = "positions (0 and 100 %: the joint's limits, red dotted)" if which == "q" else "velocities"
    peak = np.abs(pct).max()
    note = "" if which == "q" or peak >= 100 / 1.3 else f"; peak {peak:.0f} % of the limit (±100 %: off this scale)"
    fig.suptitle(f"Joint {what}{note}\nclosest to a limit: {names[c]}, {margin[k, c]:.3f} {unit_txt} from it at "
                 f"t = {t[k]:.1f} s", fontsize=11)
    save(fig, out_png)


def torques(tq: pd.DataFrame, meta: dict, t_pre: float, out_png: str | Path) -> None:
    """Each joint's torque (least-norm internal force) in % of its effort limit, per arm, the limits
    drawn; the peak with the best internal force in the title. ``meta``: the torques' provenance
    (joints, effort_nm, panel_kg)."""
    names, effort, panel_kg = meta["joints"], np.asarray(meta["effort_nm"]), meta["panel_kg"]
    fig, axes = plt.subplots(2, 1, figsize=(11, 8), sharex=True)
    peak_best = 0.0
    for side, ax in zip(("left", "right"), axes):
        cols = [c for c, n in enumerate(names) if n.startswith(side)]
        for c in cols:
            pct = 100 * tq[f"tau_{names[c]}_nm"] / effort[c]
            ax.plot(tq.t_s, pct, lw=1.2, label=f"{names[c]} (limit {effort[c]:g} N m)")
            peak_best = max(peak_best, float((100 * tq[f"tau_best_{names[c]}_nm"].abs() / effort[c]).max()))
        for y in (-100, 100):
            ax.axhline(y, color="tab:red", lw=1.2, ls="--")
        ax.text(tq.t_s.iloc[0], 100, " effort limit", color="tab:red", va="bottom", fontsize=8)
        ax.axvline(t_pre, color="0.5", lw=0.8, ls="--")
        ax.set(ylabel=f"{side} arm: torque / effort limit [%]", ylim=(-115, 115))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=4, loc="upper right")
    axes[-1].set_xlabel("t [s] (dashed grey: pre-insertion pose)")
    ratio = np.array([[100 * abs(v) / effort[c] for v in tq[f"tau_{n}_nm"]] for c, n in enumerate(names)])
    c, k = np.unravel_index(int(ratio.argmax()), ratio.shape)
    over = ratio.max() > 100
    fig.suptitle(f"Joint torques holding the {panel_kg:g} kg panel (inverse dynamics, least-norm internal force): "
                 f"peak {ratio.max():.0f} % ({names[c]}, {tq.t_s.iloc[k]:.1f} s){' - EXCEEDS the limit' if over else ''}\n"
                 f"the best internal force between the grippers brings the peak to {peak_best:.0f} %", fontsize=10)
    save(fig, out_png)


def convergence(outer: pd.DataFrame, out_png: str | Path, tolerance: float | None = None) -> None:
    """Per outer iteration of the augmented-Lagrangian loop: the constraint violations (m or rad, the
    largest residual of either kind) against the loop's ``tolerance`` (m or rad: it stops below it) and, on
    its own axis, the penalty mu (dimensionless weight)."""
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, height_ratios=[2, 1])
    ax.semilogy(outer.outer, outer.eq_violation, "o-", label="equality violation (closed chain, path)")
    ax.semilogy(outer.outer, np.maximum(outer.in_violation, 1e-16), "s-", label="inequality violation (distances, limits)")
    if tolerance is not None:
        ax.axhline(tolerance, color="k", ls=":", lw=1, label=f"tolerance {tolerance:g} (converged below both)")
    ax.set(ylabel="largest violation [m or rad]",
           title=f"Augmented Lagrangian: {len(outer)} outer, {int(outer.inner_iterations.sum())} FDDP iterations")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax2.semilogy(outer.outer, outer.mu, "^--", color="0.3")
    ax2.set(xlabel="outer iteration", ylabel="penalty mu [-]")
    ax2.grid(alpha=0.3, which="both")
    save(fig, out_png)


@dataclass(frozen=True, eq=False)
class Surroundings:
    """The static environment the arms move in: swept triangles ``tri`` (T, 3, 3) m (their cores) and capsules
    ``seg`` (a (3,) m, b (3,) m, radius m) each."""

    tri: np.ndarray
    seg: list[tuple[np.ndarray, np.ndarray, float]]


def animation(capsules: list[tuple[str, int, np.ndarray, np.ndarray, float]], poses: np.ndarray, panel: tuple,
              env: Surroundings, fps: float, title: str, out_html: str | Path) -> None:
    """MeshCat static HTML: capsules (name, body index, a, b in the body frame, r) moved by body poses
    (F, B, 4, 4); the panel (body index, pose in that body, size); the environment's swept
    triangles (their cores, translucent) and capsules (static)."""
    env_tri, env_seg = env.tri, env.seg
    vis = new_scene(title)
    for name, body, a, b, r in capsules:
        geom, pose = cylinder(a, b, r)
        node = vis[f"robot/body{body}/{name}"]
        look = material(0x4070B0) if body else material(0x8090A0, 0.3)  # the static body translucent
        node["core"].set_object(geom, look)
        node["core"].set_transform(pose)
        for k, end in enumerate((a, b)):
            node[f"cap{k}"].set_object(g.Sphere(float(r)), look)
            T = np.eye(4)
            T[:3, 3] = end
            node[f"cap{k}"].set_transform(T)
    body, in_body, size = panel
    vis[f"robot/body{body}/panel"].set_object(g.Box(list(size)), material(0xD0A030))
    vis[f"robot/body{body}/panel"].set_transform(in_body)
    if len(env_tri):
        vis["environment/faces"].set_object(g.TriangularMeshGeometry(env_tri.reshape(-1, 3),
                                                                     np.arange(3 * len(env_tri)).reshape(-1, 3)),
                                            material(0x70A070, 0.35))
    for k, (a, b, r) in enumerate(env_seg):
        geom, pose = cylinder(a, b, r)
        vis[f"environment/capsule{k}"].set_object(geom, material(0xA07050, 0.7))
        vis[f"environment/capsule{k}"].set_transform(pose)
    anim = ma.Animation(default_framerate=fps)
    for f, frame in enumerate(poses):
        with anim.at_frame(vis, f) as fv:
            for b, T in enumerate(frame):
                fv[f"robot/body{b}"].set_transform(T)
    for b, T in enumerate(poses[0]):
        vis[f"robot/body{b}"].set_transform(T)
    vis.set_animation(anim, play=True, repetitions=0)
    rig = np.eye(4)
    rig[:3, 3] = [0.4, 0.0, 0.3]
    vis["/Cameras/default"].set_transform(rig)
    vis["/Cameras/default/rotated/<object>"].set_property("position", [1.6, 1.2, 1.9])  # front right, above
    write_html(vis, out_html)
