"""Figures of the reconfigurable robot: manipulability, joint rates, the passive joint's motion,
and the 3D animation (MeshCat static HTML)."""

from __future__ import annotations

from pathlib import Path

import meshcat.animation as ma
import numpy as np
import pandas as pd

from capmap.plots.common import plt, save
from capmap.plots.scene3d import cylinder, g, material, new_scene, write_html

__all__ = ["METHOD_STYLE", "manipulability", "joint_rates", "passive_joint", "animation"]

METHOD_STYLE = {"nullspace": {"color": "tab:blue", "ls": "-", "label": "null-space method (k = kappa grad m)"},
                "pinv": {"color": "tab:red", "ls": "--", "label": "pseudo-inverse (k = 0)"}}


def manipulability(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """m(t), the smallest singular value of J and dm/dt, both methods."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 9.5), sharex=True)
    for method, df in runs.items():
        st = METHOD_STYLE.get(method, {"label": method})
        axes[0].plot(df.t_s, df.manipulability, lw=1.6, **st)
        axes[1].plot(df.t_s, df.min_singular_value, lw=1.6, **st)
        axes[2].plot(df.t_s, df.dm_dt, lw=1.4, **st)
    m0 = next(iter(runs.values())).manipulability.iloc[0]
    axes[0].axhline(m0, color="0.4", ls=":", lw=1, label=f"at capture, m = {m0:.1f}")
    axes[0].set(ylabel="manipulability m = sqrt(det(J J^T))",
                title="Long side of the closed chain: manipulability while the boom reconfigures")
    axes[1].set(ylabel="smallest singular value of J")
    axes[2].axhline(0.0, color="0.3", lw=0.8)
    axes[2].set(ylabel="dm/dt [1/s]", xlabel="t [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    save(fig, out_png)


def joint_rates(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """Each moving joint's rate, one panel per method, with the rate limit."""
    fig, axes = plt.subplots(len(runs), 1, figsize=(10, 3.8 * len(runs)), sharex=True, squeeze=False)
    for ax, (method, df) in zip(axes[:, 0], runs.items()):
        limits = df.attrs["capmap"]["rate_limits_deg_s"]
        for col in limits:
            ax.plot(df.t_s, df[col], lw=1.1, label=col.removeprefix("qd_").removesuffix("_deg_s"))
        lim = max(limits.values())
        ax.axhline(lim, color="0.2", ls=":", lw=1.2, label=f"rate limit +-{lim:g} deg/s")
        ax.axhline(-lim, color="0.2", ls=":", lw=1.2)
        peak = max(df[c].abs().max() for c in limits)
        ax.set_ylim(-1.15 * max(lim, peak), 1.15 * max(lim, peak))
        ax.set(ylabel="joint rate [deg/s]",
               title=f"{METHOD_STYLE.get(method, {}).get('label', method)}: peak {peak:.2f} deg/s")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=4, loc="lower left")
    axes[-1, 0].set_xlabel("t [s]")
    save(fig, out_png)


def passive_joint(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """The unlocked joint's rotation theta and extension d over time, with their ranges. The law is
    prescribed, so the methods move this joint alike unless one slowed its time (rate limits): the
    title says which, with the largest difference between the methods, and where they do differ."""
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    meta = next(iter(runs.values())).attrs["capmap"]
    styles = {"nullspace": dict(lw=3.0, alpha=0.45), "pinv": dict(lw=1.2, ls="--")}
    for method, df in runs.items():
        st = METHOD_STYLE.get(method, {"label": method})
        axes[0].plot(df.t_s, df.passive_theta_deg, **{**st, **styles.get(method, {})})
        axes[1].plot(df.t_s, df.passive_d_m, **{**st, **styles.get(method, {})})
    for ax, key, label in ((axes[0], "theta_deg", "rotation theta [deg]"), (axes[1], "d_m", "extension d [m]")):
        lo, hi = meta["passive_ranges"][key]
        ax.axhline(lo, color="0.3", ls=":", lw=1.2, label=f"range [{lo:g}, {hi:g}]")
        ax.axhline(hi, color="0.3", ls=":", lw=1.2)
        ax.set(ylabel=label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    frames = list(runs.values())
    if len(frames) == 2:
        a, b = frames
        t = a.t_s.to_numpy()
        dth = np.abs(np.interp(t, b.t_s, b.passive_theta_deg) - a.passive_theta_deg.to_numpy()).max()
        dd = np.abs(np.interp(t, b.t_s, b.passive_d_m) - a.passive_d_m.to_numpy()).max()
        same = dth < 1e-6 and dd < 1e-9
        by = "exactly" if dth == 0 and dd == 0 else f"to {dth:.1g} deg, {dd:.1g} m"
        note = (f"the same for both methods ({by}): the law is prescribed,\n"
                "the methods differ in the other joints (joint_rates.png) and the manipulability (manipulability.png)"
                if same else f"the methods differ by up to {dth:.3g} deg and {dd:.3g} m (one slowed its time)")
    else:
        note = "quintic rest-to-rest law"
    axes[0].set_title(f"Passive joint {meta['unlocked']}: quintic rest-to-rest law, {note}", fontsize=10)
    axes[1].set_xlabel("time t [s]")
    save(fig, out_png)


def animation(links: tuple[str, ...], segments: list[tuple[str, np.ndarray, np.ndarray]],
              frames: dict[str, np.ndarray], fps: float, unlocked: str, title: str, out_html: str | Path) -> None:
    """The robot as cylinders on its links, animated by link poses frames[method] (F, L, 4, 4)
    (link order ``links``); the null-space run opaque, any other translucent; the platform a disc."""
    vis = new_scene(title)
    opacity = {"nullspace": 1.0}
    colours = {"nullspace": 0x3070C0, "pinv": 0xD04040}
    for method in frames:
        for k, (link, a, b) in enumerate(segments):
            boom = link == unlocked  # the body the unlocked joint moves
            geom, pose = cylinder(a, b, 0.06 if boom else 0.08)
            node = vis[f"{method}/{link}/piece{k}"]
            node.set_object(geom, material(0xE0A030 if boom else colours.get(method, 0x808080),
                                           opacity.get(method, 0.25)))
            node.set_transform(pose)
    vis["platform"].set_object(g.Cylinder(0.5, 1.25), material(0x909090))
    Rx = np.eye(4)
    Rx[1:3, 1:3] = [[0, -1], [1, 0]]  # the cylinder's axis (y) to z
    Rx[2, 3] = 0.25
    vis["platform"].set_transform(Rx)
    anim = ma.Animation(default_framerate=fps)
    for method, poses in frames.items():
        for f, frame in enumerate(poses):
            with anim.at_frame(vis, f) as fv:
                for link, T in zip(links, frame):
                    fv[f"{method}/{link}"].set_transform(T)
    for method, poses in frames.items():  # the first frame also as the static pose
        for link, T in zip(links, poses[0]):
            vis[f"{method}/{link}"].set_transform(T)
    vis.set_animation(anim, play=True, repetitions=0)
    rig = np.eye(4)
    rig[:3, 3] = [0.0, 1.5, 3.0]  # the camera orbits a point above the platform, among the arms
    vis["/Cameras/default"].set_transform(rig)
    vis["/Cameras/default/rotated/<object>"].set_property("position", [9.0, 4.0, 9.0])  # (y-up frame of the camera)
    write_html(vis, out_html)
