"""Figures of the reconfigurable robot: manipulability, joint rates, the passive joint's motion,
and the 3D animation (MeshCat static HTML)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import meshcat.animation as ma
import numpy as np
import pandas as pd
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from capmap.plots.common import plt, save
from capmap.plots.scene3d import aim, cylinder, g, hide_helpers, material, new_scene, write_html

__all__ = ["METHOD_STYLE", "CLOSURE_TOL", "manipulability", "joint_rates", "passive_joint", "animation"]

METHOD_STYLE = {"nullspace": {"color": "tab:blue", "ls": "-", "label": "null-space method"},
                "pinv": {"color": "tab:red", "ls": "--", "label": "pseudo-inverse"}}
NAMES = {"nullspace": "null-space method", "pinv": "pseudo-inverse"}
CLOSURE_TOL = 1e-9  # m and rad: the loop counts as closed below this (the workflow test's acceptance)
GAIN_BAND = dict(color="tab:blue", alpha=0.08, lw=0)  # the null-space gain above its floor


def _style(method: str) -> dict:
    return METHOD_STYLE.get(method, {"label": method})


def _name(method: str) -> str:
    return NAMES.get(method, method)


def _num(v: float) -> str:  # what a reader needs: whole numbers from 10 on, else 2 significant digits ('71', '0.51')
    return f"{v:.0f}" if abs(v) >= 10 else f"{v:.2g}"


def _above_floor(df: pd.DataFrame) -> np.ndarray:
    """Where the null-space gain κ exceeds its floor κ₀ w (column ``kappa_floor``, when given): the task motion
    alone would lower m there, and the gain's other part holds dm/dt at κ₀ w |N∇m|²."""
    if "kappa_floor" not in df or "kappa" not in df:
        return np.zeros(len(df), dtype=bool)
    floor = df.kappa_floor.to_numpy()
    return df.kappa.to_numpy() > floor * (1 + 1e-6) + 1e-12 * max(1.0, floor.max())


def _band(ax, df: pd.DataFrame) -> float | None:
    """The periods the null-space gain is above its floor, shaded; the end of the last one while the law moves (NaN:
    none; None: nothing shaded)."""
    where = _above_floor(df)
    if not where.any():
        return None
    ax.fill_between(df.t_s, 0, 1, where=where, transform=ax.get_xaxis_transform(), step="mid", **GAIN_BAND)
    floor = df.kappa_floor.to_numpy()  # an end while the law still moves (not its rest at the end): a kink in dm/dt
    ends = [k + 1 for k in np.flatnonzero(where[:-1] & ~where[1:]) if floor[k + 1] > 0.01 * floor.max()]
    return float(df.t_s.iloc[ends[-1]]) if ends else float("nan")


def _m_verdict(method: str, df: pd.DataFrame) -> str:
    """What m did in a run, in a few words: its start and end, and either that it never fell or its lowest value."""
    m, dm = df.manipulability.to_numpy(), df.dm_dt.to_numpy()
    falls = int((dm < -1e-9 * max(1.0, np.abs(dm).max())).sum())
    k = int(np.argmin(m))
    how = ", never falling" if not falls else f", lowest {_num(m[k])}" if k not in (0, len(m) - 1) else ""
    status = df.attrs.get("capmap", {}).get("status", "completed")
    stop = f" ({status} at {_num(df.t_s.iloc[-1])} s)" if status != "completed" else ""
    return f"{_name(method)} {_num(m[0])} → {_num(m[-1])}{how}{stop}"


def manipulability(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """m(t) (each method's verdict in the one-line title), the smallest singular value of J and dm/dt, both
    methods, with the periods the null-space method pushes back against a task that alone would lower m (its gain
    above its floor) shaded where dm/dt is drawn."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 10), sharex=True, height_ratios=(1.3, 1, 1))
    sw = None
    for method, df in runs.items():
        sw = _band(axes[2], df) or sw
        for ax, col in zip(axes, ("manipulability", "min_singular_value", "dm_dt")):
            ax.plot(df.t_s, df[col], lw=1.6, **{**_style(method), "label": _name(method)})
    m0 = next(iter(runs.values())).manipulability.iloc[0]
    axes[0].axhline(m0, color="0.4", ls=":", lw=1, label=f"m at capture ({_num(m0)} m³)")
    axes[0].set(ylabel="manipulability m [m³]")
    axes[0].legend(fontsize=9, loc="upper left")
    axes[1].set(ylabel="smallest singular value of J\n(mixed units)")
    axes[1].set_title("how far from a singularity: the smallest singular value, lowest " + ", ".join(
        f"{_num(df.min_singular_value.min())} ({_name(k)})" for k, df in runs.items()), fontsize=10)
    axes[2].axhline(0.0, color="0.3", lw=0.8)
    axes[2].set(ylabel="dm/dt [m³/s]\n(< 0: towards a singularity)", xlabel="time t [s]")
    if sw is not None:
        axes[2].legend(handles=[Patch(**GAIN_BAND, label="null-space method pushing back")], fontsize=9, loc="lower left")
        if np.isfinite(sw):
            axes[2].axvline(sw, color="tab:blue", ls=":", lw=1)
        axes[2].set_title((f"until {_num(sw)} s" if np.isfinite(sw) else "where shaded,") + " the task alone would lower "
                          "m; the null-space method pushes back", fontsize=10)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle("Manipulability m: " + "; ".join(_m_verdict(m, df) for m, df in runs.items()), fontsize=12)
    save(fig, out_png)


def _joint_name(col: str) -> str:
    """'qd_arm2_j4_deg_s' -> 'arm2.J4'."""
    arm, j = col.removeprefix("qd_").removesuffix("_deg_s").rsplit("_", 1)
    return f"{arm}.{j.upper()}"


def _alike(runs: dict[str, pd.DataFrame]) -> list[str]:
    """Pairs of joints whose rates are identical in every run (e.g. two coaxial axes), as 'arm1.J6 = arm2.J6'."""
    df0 = next(iter(runs.values()))
    cols = list(df0.attrs["capmap"]["rate_limits_deg_s"])
    return [f"{_joint_name(b)} = {_joint_name(a)}" for i, a in enumerate(cols) for b in cols[i + 1:]
            if all(np.allclose(df[a], df[b], rtol=0, atol=1e-9 * max(1.0, df[a].abs().max())) for df in runs.values())]


def _colour(col: str) -> str:  # one colour per joint number, in every arm
    return f"C{(int(_joint_name(col)[-1]) - 1) % 10}"


def _rates_panel(ax, df: pd.DataFrame, limits: dict, cols: list[str], top: float) -> tuple[float, str]:
    """One method's rates of one arm's joints with their limits; the largest |rate| / limit and its joint."""
    for c in sorted(cols, key=_joint_name):  # J1 first in its legend
        ax.plot(df.t_s, df[c], lw=1.4, color=_colour(c), label=_joint_name(c).split(".")[1])
    for lim in sorted(set(np.round([limits[c] for c in cols], 9))):
        for sign in (1, -1):
            ax.axhline(sign * lim, color="0.2", ls=":", lw=1.3)
    c = max(cols, key=lambda c: df[c].abs().max() / limits[c])
    ax.set(ylim=(-top, top))
    ax.grid(alpha=0.3)
    return float(df[c].abs().max() / limits[c]), _joint_name(c)


def joint_rates(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """Each moving joint's rate, one panel per method (rows) and arm (columns), one colour per joint number (each
    column's joints in its own legend), with the rate limits and the periods the null-space method pushes back.
    Each panel's peak in its title, the verdict against the limits in the figure's one-line title."""
    limits = next(iter(runs.values())).attrs["capmap"]["rate_limits_deg_s"]
    arms = list(dict.fromkeys(_joint_name(c).split(".")[0] for c in limits))
    fig, axes = plt.subplots(len(runs), len(arms), figsize=(6 * len(arms) + 2.4, 1.6 + 3.4 * len(runs)), sharex=True,
                             sharey=True, squeeze=False)
    top, best, sw = 1.15 * max(max(limits.values()), *(df[list(limits)].abs().max().max() for df in runs.values())), {}, None
    for row, (method, df) in zip(axes, runs.items()):
        for ax, arm in zip(row, arms):
            sw = _band(ax, df) or sw
            peak, joint = _rates_panel(ax, df, limits, [c for c in limits if _joint_name(c).startswith(arm + ".")], top)
            best[method] = max(best.get(method, (0.0, "")), (peak, joint))
            ax.set_title(f"{_name(method)}, {arm}: peak {_num(100 * peak)} % of the limit ({joint.split('.')[1]})",
                         fontsize=10)
        row[0].set_ylabel("joint rate [deg/s]")
    for ax in axes[-1]:
        ax.set_xlabel("time t [s]")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=6, fontsize=9, frameon=False)
    handles = [Line2D([], [], color="0.2", ls=":", lw=1.3, label="rate limit ±" + ", ".join(
        f"{v:g}" for v in sorted(set(np.round(list(limits.values()), 9)))) + " deg/s")]
    if sw is not None:
        handles.append(Patch(**GAIN_BAND, label="null-space method\npushing back" + (f" (until {_num(sw)} s)"
                                                                                    if np.isfinite(sw) else "")))
    handles += [Line2D([], [], ls="none", label=f"{a.replace(' = ', ' turns as ')}\n(drawn in both)") for a in _alike(runs)]
    fig.legend(handles=handles, loc="center right", fontsize=9, frameon=False)
    within = max(p for p, _ in best.values()) <= 1 + 1e-9
    fig.suptitle(f"Joint rates {'stay within' if within else 'exceed'} their limits: peak "
                 + ", ".join(f"{_num(100 * p)} % ({_name(m)})" for m, (p, _) in best.items()), fontsize=12)
    save(fig, out_png, rect=(0, 0, 1 - 2.4 / fig.get_figwidth(), 1))


def _closure(runs: dict[str, pd.DataFrame]) -> str:
    """'the loop stays closed (< 1e-14 m)' (the largest position error's order of magnitude; the rotation's too when
    larger in rad), or how far it opens."""
    pos = max(df.closure_pos_err_m.max() for df in runs.values())
    rot = max(df.closure_rot_err_rad.max() for df in runs.values())
    if pos > CLOSURE_TOL or rot > CLOSURE_TOL:
        return f"the loop opens (up to {pos:.1g} m, {rot:.1g} rad)"
    bound = 10.0 ** np.ceil(np.log10(max(pos, rot, 1e-300)))
    return f"the loop stays closed (< {bound:.0e}".replace("e-0", "e-") + (" m)" if pos >= rot else " m, rad)")


def passive_joint(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """The unlocked joint's rotation θ and extension d against their ranges: one curve when every run moves it
    alike (the law is prescribed), one per method when a run slowed its time or stopped. The one-line title: the
    smallest margin to each range and whether the loop stays closed in every run."""
    meta = next(iter(runs.values())).attrs["capmap"]
    frames = list(runs.items())
    ref = frames[0][1]
    alike = all(len(df) == len(ref) and np.allclose(df.t_s, ref.t_s) and np.allclose(df.passive_theta_deg,
                ref.passive_theta_deg) and np.allclose(df.passive_d_m, ref.passive_d_m) for _, df in frames)
    shown = frames[:1] if alike else frames
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), sharex=True)
    margins = []
    for ax, key, col, label, unit in ((axes[0], "theta_deg", "passive_theta_deg", "rotation θ", "°"),
                                      (axes[1], "d_m", "passive_d_m", "extension d", " m")):
        for method, df in shown:
            st = {"color": "black", "label": "its law (both methods alike)"} if alike else _style(method)
            ax.plot(df.t_s, df[col], lw=1.8, **st)
        lo, hi = meta["passive_ranges"][key]
        for y in (lo, hi):
            ax.axhline(y, color="tab:red", ls=":", lw=1.3, label="range of the joint" if y == lo else None)
        vals = np.concatenate([df[col].to_numpy() for _, df in shown])
        margins.append(f"{min(vals.min() - lo, hi - vals.max()):.2g}{unit}")
        ends = " / ".join(f"{df[col].iloc[-1]:.2g}" for _, df in shown)  # one per method when they differ
        ax.set(ylabel=f"{label} [{unit.strip()}]", xlabel="time t [s]", ylim=(lo - 0.08 * (hi - lo), hi + 0.08 * (hi - lo)))
        ax.set_title(f"{label}: {vals[0]:.2g} → {ends}{unit}, range {lo:g} to {hi:g}{unit}".replace("-", "−"), fontsize=10)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=9, loc="lower right")
    differ = "" if alike else "; the methods move it differently"
    fig.suptitle(f"Passive joint {meta['unlocked']} stays at least {' / '.join(margins)} inside its ranges; {_closure(runs)}"
                 f"{differ}", fontsize=12)
    save(fig, out_png)


@dataclass(frozen=True, eq=False)
class ReconfigMotion:
    """The reconfiguration to animate: per method, the poses (F, L, 4, 4) of the ``links`` sampled at ``fps`` from
    t = 0 and the manipulability m (F,) at those frames; the ``unlocked`` joint; the ``capture``: the two links
    (``links`` holds them) held together, which closes the loop."""

    links: tuple[str, ...]
    poses: dict[str, np.ndarray]
    m: dict[str, np.ndarray]
    fps: float
    unlocked: str
    capture: tuple[str, str]


RUN_COLOUR, RUN_NAME = {"nullspace": 0x3070C0, "pinv": 0xD04040}, {"nullspace": "null-space", "pinv": "pseudo-inverse"}
RUN_HUE = {0x3070C0: "blue", 0xD04040: "red"}
BOOM, CAPTURE, IDLE, PLATFORM = 0xE0A030, 0x8A3FC0, 0x9A9A9A, 0x707070
APART_M = 0.1  # the runs count as apart once the same joint of the two is this far from itself, m


def _legend(motion: ReconfigMotion, runs: list[str], idle: list[str]) -> tuple:
    """The colours: each run (the first opaque, the others sheaths), the boom, the capture, the idle arms, the platform."""
    secs = {r: (len(p) - 1) / motion.fps for r, p in motion.poses.items()}
    keys = [(RUN_COLOUR.get(r, 0x808080), 1.0 if r == runs[0] else 0.3,
             f"{RUN_NAME.get(r, r)} run, {secs[r]:.1f} s" + ("" if r == runs[0] else " (translucent sheath)")) for r in runs]
    keys += [(BOOM, 1.0, f"boom: unlocked joint {motion.unlocked}"),
             (CAPTURE, 1.0, "capture: " + " held by ".join(motion.capture))]
    return tuple(keys + [(IDLE, 0.35, f"{', '.join(idle)}: not in the loop")] * bool(idle) + [(PLATFORM, 1.0, "platform")])


def _apart(motion: ReconfigMotion, moving: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Per frame (with two runs): how far apart the same ``moving`` link of the two runs is at most (m), and which."""
    at = [p[np.minimum(np.arange(max(len(q) for q in motion.poses.values())), len(p) - 1)][:, moving][..., :3, 3]
          for p in motion.poses.values()]
    if len(at) != 2 or not moving:
        return np.zeros(len(at[0])), np.zeros(len(at[0]), dtype=int)
    gap = np.linalg.norm(at[0] - at[1], axis=2)
    return gap.max(axis=1), np.asarray(moving)[gap.argmax(axis=1)]


def _watch(motion: ReconfigMotion, runs: list[str], gap: np.ndarray) -> tuple[str, float]:
    """What to watch (from when the runs part) and when the view opens: where they are half their widest apart."""
    if len(runs) != 2 or gap.max() < APART_M:
        return "", 0.0
    hue = [RUN_HUE.get(RUN_COLOUR.get(r), r) for r in runs]
    part, start = np.argmax(gap >= APART_M) / motion.fps, np.argmax(gap >= gap.max() / 2) / motion.fps
    return (f"Watch the {hue[1]} sheath ({RUN_NAME.get(runs[1], runs[1])}) leave the {hue[0]} arms from {part:.0f} s "
            f"(opens at {start:.0f} s)"), float(start)


def animation(motion: ReconfigMotion, segments: list[tuple[str, np.ndarray, np.ndarray]], title: str,
              out_html: str | Path) -> None:
    """The robot as cylinders on its links (``segments``: link, a, b in the link frame) moved by ``motion``: the
    links both runs move alike drawn once, the first run opaque, any other as a translucent sheath around it (it
    shows where the runs coincide), the boom the unlocked joint moves orange, the capture a cube, the arms outside
    the loop faint grey, the platform a disc; the camera on the loop, on a pale background. Over the view: ``title``
    (its first line; the others under it), what to watch, the simulated time with each run's manipulability and how far
    apart the runs are, a live plot of m(t), a legend; the view opens where the runs are half their widest apart."""
    runs, links, (held, _) = list(motion.poses), motion.links, motion.capture
    first = motion.poses[runs[0]]
    shared = {link for i, link in enumerate(links)
              if all(p.shape == first.shape and np.allclose(p[:, i], first[:, i]) for p in motion.poses.values())}
    loop = {link.split(".")[0] for link in motion.capture}
    idle = sorted({link.split(".")[0] for link, _, _ in segments} - loop)
    gap, where = _apart(motion, [i for i, link in enumerate(links) if link not in shared])
    watch, start = _watch(motion, runs, gap)
    head, *lines = title.split("\n")
    series = tuple((RUN_NAME.get(r, r), RUN_COLOUR.get(r, 0x808080), tuple(m)) for r, m in motion.m.items())
    vis = new_scene(head, light=True, lines=tuple(lines) + ((watch,) if watch else ()), legend=_legend(motion, runs, idle),
                    fps=motion.fps, frame_text=_readout(motion, gap, [links[k] for k in where]), start=start,
                    inset=("manipulability m", series, (len(first) - 1) / motion.fps))
    layers = [("shared", first, shared)] + [(r, motion.poses[r], set(links) - shared) for r in runs]
    for root, _, mine in layers:
        sheath = root not in ("shared", runs[0])
        look = {"opacity": 0.3 if sheath else 1.0, "colour": RUN_COLOUR.get(runs[0] if root == "shared" else root)}
        for k, (link, a, b) in enumerate(segments):
            if link in mine:
                still = link.split(".")[0] in idle
                colour = BOOM if link == motion.unlocked else IDLE if still else look["colour"]
                geom, pose = cylinder(a, b, (0.06 if link == motion.unlocked else 0.08) * (1.5 if sheath else 1.0))
                vis[f"{root}/{link}/piece{k}"].set_object(geom, material(colour, 0.35 if still else look["opacity"]))
                vis[f"{root}/{link}/piece{k}"].set_transform(pose)
        if held in mine:
            vis[f"{root}/{held}/capture"].set_object(g.Box([0.36 if sheath else 0.3] * 3), material(CAPTURE, look["opacity"]))
    vis["platform/disc"].set_object(g.Cylinder(0.5, 1.25), material(PLATFORM))
    Rx = np.eye(4)
    Rx[1:3, 1:3] = [[0, -1], [1, 0]]  # the cylinder's axis (y) to z
    Rx[2, 3] = 0.25
    vis["platform/disc"].set_transform(Rx)
    anim = ma.Animation(default_framerate=motion.fps)
    for root, poses, mine in layers:
        for f, frame in enumerate(poses):
            with anim.at_frame(vis, f) as fv:
                for link, T in zip(links, frame):
                    if link in mine:
                        fv[f"{root}/{link}"].set_transform(T)
        for link, T in zip(links, poses[0]):  # the first frame also as the static pose
            if link in mine:
                vis[f"{root}/{link}"].set_transform(T)
    vis.set_animation(anim, play=True, repetitions=2**31 - 1)  # looped until the page is closed
    ends = [(links.index(link), e) for link, a, b in segments if link.split(".")[0] in loop for e in (a, b)]
    pts = np.array([T[i, :3, :3] @ e + T[i, :3, 3] for p in motion.poses.values() for T in p[::10] for i, e in ends])
    hide_helpers(vis)  # a space robot: no floor
    aim(vis, (*runs, "shared", "platform"), (pts.min(axis=0) + pts.max(axis=0)) / 2,
        0.45 * np.linalg.norm(np.ptp(pts, axis=0)) * np.array([1.0, -1.0, 0.55]), right=0.12)
    write_html(vis, out_html)


def _readout(motion: ReconfigMotion, gap: np.ndarray, where: list[str]) -> tuple[str, ...]:
    """Per frame: each run's manipulability m (and its change since the capture) and, with two runs, how far apart
    the same joint of the two runs is at most (``gap`` m, at the link ``where``)."""
    texts = []
    for f in range(len(gap)):
        m = {r: v[min(f, len(v) - 1)] for r, v in motion.m.items()}
        pct = {r: f"{round(100 * (x / motion.m[r][0] - 1)):+d}".replace("-", "−") for r, x in m.items()}
        words = ", ".join(f"{RUN_NAME.get(r, r)} {x:.1f} ({pct[r]} %)" for r, x in m.items())
        apart = f"\nfarthest joint: {where[f]} of the two runs {gap[f]:.2f} m apart" if len(m) == 2 and gap.max() > 0 else ""
        texts.append(f"m: {words}{apart}")
    return tuple(texts)
