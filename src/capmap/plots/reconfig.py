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


def _style(method: str) -> dict:
    return METHOD_STYLE.get(method, {"label": method})


def _joint_name(col: str) -> str:
    """'qd_arm2_j4_deg_s' -> 'arm2.J4'."""
    arm, j = col.removeprefix("qd_").removesuffix("_deg_s").rsplit("_", 1)
    return f"{arm}.{j.upper()}"


def _m_verdict(method: str, df: pd.DataFrame) -> str:
    """What m did in a run: its start and end, its minimum, the steps it fell."""
    m, dm = df.manipulability.to_numpy(), df.dm_dt.to_numpy()
    falls = int((dm < -1e-9 * max(1.0, np.abs(dm).max())).sum())
    k = int(np.argmin(m))
    low = f", minimum {m[k]:.3g} at {df.t_s.iloc[k]:.3g} s" if k not in (0, len(m) - 1) else ""
    fell = f"falling in {falls} of {len(m) - 1} steps" if falls else "never falling (dm/dt ≥ 0)"
    status = df.attrs.get("capmap", {}).get("status", "completed")
    if status != "completed":
        fell += f"; {status} at {df.t_s.iloc[-1]:.3g} s"
    return f"{_style(method)['label'].split(' (')[0]}: m {m[0]:.3g} → {m[-1]:.3g}{low}, {fell}"


def manipulability(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """m(t), the smallest singular value of J and dm/dt, both methods; the verdict (what m did under
    each method) in the title."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 10), sharex=True)
    for method, df in runs.items():
        st = _style(method)
        axes[0].plot(df.t_s, df.manipulability, lw=1.6, **st)
        axes[1].plot(df.t_s, df.min_singular_value, lw=1.6, **st)
        axes[2].plot(df.t_s, df.dm_dt, lw=1.4, **st)
    m0 = next(iter(runs.values())).manipulability.iloc[0]
    axes[0].axhline(m0, color="0.4", ls=":", lw=1, label=f"m at capture ({m0:.3g})")
    axes[0].set(ylabel="manipulability m = √det(J Jᵀ) [–]")
    axes[1].set(ylabel="smallest singular value of J [–]")
    axes[2].axhline(0.0, color="0.3", lw=0.8)
    axes[2].set(ylabel="dm/dt [1/s]\n(< 0: towards a singularity)", xlabel="time t [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=9, loc="upper left")
    n = len(next(iter(runs.values())).attrs["capmap"].get("moving_joints", ())) or "n"
    fig.suptitle(f"Manipulability of the long side (J: its 6 × {n} Jacobian, SI units) while the boom reconfigures\n"
                 + "\n".join(_m_verdict(m, df) for m, df in runs.items()), fontsize=11)
    save(fig, out_png)


def _distinct(df: pd.DataFrame, cols: list[str]) -> list[list[str]]:
    """The rate columns grouped by identical series (e.g. two coaxial joints the pseudo-inverse moves alike)."""
    groups: list[list[str]] = []
    for c in cols:
        same = next((g for g in groups if np.allclose(df[g[0]], df[c], rtol=0, atol=1e-9)), None)
        if same is None:
            groups.append([c])
        else:
            same.append(c)
    return groups


def joint_rates(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """Each moving joint's rate (colour: the joint number, solid/dashed: the arm), one panel per method,
    with the rate limits; a joint's rate identical to another's drawn once. The peak, its joint and its
    share of the limit in each panel's title; one legend beside the panels."""
    fig, axes = plt.subplots(len(runs), 1, figsize=(12, 1.0 + 3.6 * len(runs)), sharex=True, squeeze=False)
    peaks = []
    for ax, (method, df) in zip(axes[:, 0], runs.items()):
        limits = df.attrs["capmap"]["rate_limits_deg_s"]
        arms = sorted({_joint_name(c).split(".")[0] for c in limits})
        for group in _distinct(df, list(limits)):
            arm, j = _joint_name(group[0]).split(".")
            ax.plot(df.t_s, df[group[0]], lw=1.2, color=f"C{(int(j[1:]) - 1) % 10}",
                    ls=("-", "--", "-.", ":")[arms.index(arm) % 4], label=" = ".join(map(_joint_name, group)))
        for lim in sorted(set(np.round(list(limits.values()), 9))):
            for sign in (1, -1):
                ax.axhline(sign * lim, color="0.2", ls=":", lw=1.3, label=f"rate limit ±{lim:g} deg/s" if sign > 0 else None)
        peak_col = max(limits, key=lambda c: df[c].abs().max())
        peak = df[peak_col].abs().max()
        peaks.append(peak / limits[peak_col])
        top = 1.15 * max(max(limits.values()), peak)
        ax.set(ylim=(-top, top), ylabel="joint rate [deg/s]")
        ax.set_title(f"{_style(method)['label']}: peak {peak:.3g} deg/s ({_joint_name(peak_col)}), "
                     f"{100 * peak / limits[peak_col]:.3g} % of its limit", fontsize=10)
        ax.grid(alpha=0.3)
    legend = {lab: h for ax in axes[:, 0] for h, lab in zip(*ax.get_legend_handles_labels())}
    fig.legend(legend.values(), legend.keys(), fontsize=8.5, loc="center right", frameon=False)
    axes[-1, 0].set_xlabel("time t [s]")
    within = max(peaks) <= 1 + 1e-9
    fig.suptitle(f"Joint rates of the long side, rest to rest: {'within' if within else 'beyond'} the rate limits, "
                 "peak " + ", ".join(f"{100 * p:.3g} % ({_style(m)['label'].split(' (')[0]})"
                                     for m, p in zip(runs, peaks)) + " of the limit", fontsize=12)
    save(fig, out_png, rect=(0, 0, 0.85, 1))


def passive_joint(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """The reconfiguration as commanded: the unlocked joint's rotation theta and extension d against their
    ranges (one curve: the law is prescribed, so every method that keeps its time moves it alike; one
    curve per method when a method slowed its time), and the loop-closure error of the whole closed
    chain, position and rotation, per method (log scale): the chain stays closed while the boom moves."""
    fig, axes = plt.subplots(2, 2, figsize=(12, 6.8), sharex=True)
    meta = next(iter(runs.values())).attrs["capmap"]
    frames = list(runs.items())
    t0 = frames[0][1].t_s.to_numpy()
    alike = all(len(df) == len(t0) and np.allclose(df.t_s, t0) and np.allclose(df.passive_theta_deg,
                frames[0][1].passive_theta_deg) and np.allclose(df.passive_d_m, frames[0][1].passive_d_m)
                for _, df in frames)
    shown = frames[:1] if alike else frames
    for (ax, key, col, label) in ((axes[0, 0], "theta_deg", "passive_theta_deg", "rotation θ [deg]"),
                                  (axes[1, 0], "d_m", "passive_d_m", "extension d [m]")):
        for method, df in shown:
            st = {"color": "black", "label": "the law (every method)"} if alike else _style(method)
            ax.plot(df.t_s, df[col], lw=1.6, **st)
        lo, hi = meta["passive_ranges"][key]
        ax.axhline(lo, color="tab:red", ls=":", lw=1.3, label="range of the joint")
        ax.axhline(hi, color="tab:red", ls=":", lw=1.3)
        vals = np.concatenate([df[col].to_numpy() for _, df in shown])
        margin = min(vals.min() - lo, hi - vals.max())
        unit = label.split("[")[1].rstrip("]")
        ax.set(ylabel=label, ylim=(lo - 0.08 * (hi - lo), hi + 0.08 * (hi - lo)))
        ends = " / ".join(f"{df[col].iloc[-1]:.3g}" for _, df in shown)  # one per method when they differ
        ax.set_title(f"{label.split(' [')[0]}: {vals[0]:.3g} → {ends} {unit} in [{lo:g}, {hi:g}], "
                     f"margin ≥ {margin:.3g} {unit}", fontsize=10)
        ax.grid(alpha=0.3)
    _closure_panels(axes[:, 1], runs)
    legend = {lab: h for ax in axes.ravel() for h, lab in zip(*ax.get_legend_handles_labels())}
    fig.legend(legend.values(), legend.keys(), loc="lower center", ncol=len(legend), fontsize=9)
    for ax in axes[1]:
        ax.set_xlabel("time t [s]")
    same = ("the same for both methods by construction (prescribed law, neither slowed its time)" if alike
            else "the methods move it differently (a run slowed its time or stopped early: summary.csv)")
    fig.suptitle(f"Passive joint {meta['unlocked']}: quintic rest-to-rest law within its ranges, {same};\n"
                 f"the closed chain stays closed to {_closure_max(runs):.2g} m", fontsize=11)
    save(fig, out_png, rect=(0, 0.05, 1, 1))


def _closure_max(runs: dict[str, pd.DataFrame]) -> float:
    return max(df.closure_pos_err_m.max() for df in runs.values())


def _closure_panels(axes, runs: dict[str, pd.DataFrame]) -> None:
    """The whole loop's closure error (the full model, both chains evaluated independently) per method:
    position (m) and rotation (rad), the largest in each of 80 windows (a line, not a block of rounding
    noise), log scale."""
    for ax, col, label in ((axes[0], "closure_pos_err_m", "loop closure error, position [m]"),
                           (axes[1], "closure_rot_err_rad", "loop closure error, rotation [rad]")):
        for method, df in runs.items():
            t = df.t_s.to_numpy()
            k = np.minimum((80 * (t - t[0]) / max(t[-1] - t[0], 1e-12)).astype(int), 79)
            starts = np.flatnonzero(np.r_[True, np.diff(k) > 0])
            peak = np.maximum(np.maximum.reduceat(df[col].to_numpy(), starts), 1e-18)
            ax.semilogy(np.r_[t[starts], t[-1]], np.r_[peak, peak[-1]], drawstyle="steps-post", lw=1.4,
                        **_style(method))
        worst = max(df[col].max() for df in runs.values())
        unit = label.split("[")[1].rstrip("]")
        ax.set(ylabel=label + "\n(largest in each window)", ylim=(1e-18, max(1e-12, 30 * worst)))
        ax.set_title(f"closure error, {label.split(', ')[1].split(' [')[0]}: at most {worst:.2g} {unit}"
                     + (" (double-precision rounding)" if worst < 1e-12 else ""), fontsize=10)
        ax.grid(alpha=0.3)


def animation(links: tuple[str, ...], segments: list[tuple[str, np.ndarray, np.ndarray]],
              frames: dict[str, np.ndarray], fps: float, unlocked: str, title: str, out_html: str | Path) -> None:
    """The robot as cylinders on its links, animated by link poses frames[method] (F, L, 4, 4)
    (link order ``links``, sampled at ``fps`` from t = 0); the null-space run opaque, any other translucent; the
    platform a disc. Over the view: ``title`` (its first line; the others under it), a legend of the colours
    and the simulated time as it plays (looped)."""
    opacity = {"nullspace": 1.0}
    colours = {"nullspace": 0x3070C0, "pinv": 0xD04040}
    what = {"nullspace": "null-space method", "pinv": "pseudo-inverse (translucent ghost)"}
    legend = [(colours.get(m, 0x808080), opacity.get(m, 0.25),
               f"{what.get(m, m)}: arms, {(len(p) - 1) / fps:.1f} s") for m, p in frames.items()]
    legend += [(0xE0A030, 1.0, f"boom moved by the unlocked joint {unlocked}"), (0x909090, 1.0, "platform")]
    head, *lines = title.split("\n")
    vis = new_scene(head, lines=tuple(lines), legend=tuple(legend))
    for method in frames:
        for k, (link, a, b) in enumerate(segments):
            boom = link == unlocked  # the body the unlocked joint moves
            geom, pose = cylinder(a, b, 0.06 if boom else 0.08)
            node = vis[f"{method}/{link}/piece{k}"]
            node.set_object(geom, material(0xE0A030 if boom else colours.get(method, 0x808080),
                                           opacity.get(method, 0.25)))
            node.set_transform(pose)
    vis["platform/disc"].set_object(g.Cylinder(0.5, 1.25), material(0x909090))
    Rx = np.eye(4)
    Rx[1:3, 1:3] = [[0, -1], [1, 0]]  # the cylinder's axis (y) to z
    Rx[2, 3] = 0.25
    vis["platform/disc"].set_transform(Rx)
    anim = ma.Animation(default_framerate=fps)
    for method, poses in frames.items():
        for f, frame in enumerate(poses):
            with anim.at_frame(vis, f) as fv:
                for link, T in zip(links, frame):
                    fv[f"{method}/{link}"].set_transform(T)
    for method, poses in frames.items():  # the first frame also as the static pose
        for link, T in zip(links, poses[0]):
            vis[f"{method}/{link}"].set_transform(T)
    vis.set_animation(anim, play=True, repetitions=2**31 - 1)  # looped until the page is closed
    ends = [(links.index(link), e) for link, a, b in segments for e in (a, b)]
    pts = np.array([T[i, :3, :3] @ e + T[i, :3, 3] for p in frames.values() for T in p[::10] for i, e in ends])
    shift = np.eye(4)  # MeshCat's camera orbits the origin: the scene, grid and axes moved to centre the motion
    shift[:3, 3] = -(pts.min(axis=0) + pts.max(axis=0)) / 2
    for root in (*frames, "platform", "/Grid", "/Axes"):
        vis[root].set_transform(shift)
    x, y, z = 0.55 * np.linalg.norm(np.ptp(pts, axis=0)) * np.array([1.0, -1.0, 0.5])  # front right, above: all in view
    vis["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])  # (the camera's frame: y up)
    write_html(vis, out_html)
