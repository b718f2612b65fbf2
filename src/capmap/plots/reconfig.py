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

METHOD_STYLE = {"nullspace": {"color": "tab:blue", "ls": "-", "label": "null-space method: q̇ = J⁺ẋ + κ (I − J⁺J) ∇m"},
                "pinv": {"color": "tab:red", "ls": "--", "label": "pseudo-inverse: q̇ = J⁺ẋ"}}
NAMES = {"nullspace": "null-space method", "pinv": "pseudo-inverse"}
CLOSURE_TOL = 1e-9  # m and rad: the loop counts as closed below this (the workflow test's acceptance)
GAIN_BAND = dict(color="tab:blue", alpha=0.08, lw=0)  # the null-space gain above its floor


def _style(method: str) -> dict:
    return METHOD_STYLE.get(method, {"label": method})


def _name(method: str) -> str:
    return NAMES.get(method, method)


def _chain(joints: list[str]) -> str:
    """['arm2.J1', ..., 'arm2.J6', 'arm1.J6', ..., 'arm1.J3'] -> 'arm2.J1–J6 → arm1.J6–J3'."""
    groups: list[list[str]] = []
    for j in joints:
        arm, name = j.split(".")
        if groups and groups[-1][0] == arm:
            groups[-1].append(name)
        else:
            groups.append([arm, name])
    return " → ".join(f"{a}.{n[0]}–{n[-1]}" if len(n) > 1 else f"{a}.{n[0]}" for a, *n in groups)


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
    """What m did in a run: its start and end, its minimum, the steps it fell."""
    m, dm = df.manipulability.to_numpy(), df.dm_dt.to_numpy()
    falls = int((dm < -1e-9 * max(1.0, np.abs(dm).max())).sum())
    k = int(np.argmin(m))
    low = f", minimum {m[k]:.3g} at {df.t_s.iloc[k]:.3g} s" if k not in (0, len(m) - 1) else ""
    fell = f"falling in {falls} of {len(m) - 1} steps" if falls else "never falling (dm/dt ≥ 0)"
    status = df.attrs.get("capmap", {}).get("status", "completed")
    if status != "completed":
        fell += f"; {status} at {df.t_s.iloc[-1]:.3g} s"
    return f"{_name(method)}: m {m[0]:.3g} → {m[-1]:.3g}{low}, {fell}"


def manipulability(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """m(t) (the verdict of each method in the title), the smallest singular value of J and dm/dt, both
    methods, with the periods the null-space gain is above its floor (where dm/dt changes its law: the kink)."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 10.5), sharex=True, height_ratios=(1.3, 1, 1))
    sw = None
    for method, df in runs.items():
        st = _style(method)
        sw = _band(axes[2], df) or sw
        for ax, col in zip(axes, ("manipulability", "min_singular_value", "dm_dt")):
            ax.plot(df.t_s, df[col], lw=1.6, **st)
    meta = next(iter(runs.values())).attrs["capmap"]
    m0 = next(iter(runs.values())).manipulability.iloc[0]
    axes[0].axhline(m0, color="0.4", ls=":", lw=1, label=f"m at capture ({m0:.3g} m³)")
    axes[0].set(ylabel="manipulability m = √det(J Jᵀ) [m³]")
    axes[1].set(ylabel="smallest singular value σ_min of J\n[m/rad and 1 mixed: no single unit]")
    axes[1].set_title("σ_min (start → lowest → end): " + "; ".join(
        f"{_name(k)} {df.min_singular_value.iloc[0]:.3g} → {df.min_singular_value.min():.3g} at "
        f"{df.t_s.iloc[int(df.min_singular_value.argmin())]:.3g} s → {df.min_singular_value.iloc[-1]:.3g}"
        for k, df in runs.items()), fontsize=9.5)
    axes[2].axhline(0.0, color="0.3", lw=0.8)
    axes[2].set(ylabel="dm/dt [m³/s]\n(< 0: towards a singularity)", xlabel="time t [s]")
    if sw is not None and np.isfinite(sw):
        axes[2].axvline(sw, color="tab:blue", ls=":", lw=1)
        axes[2].set_title(f"null-space method: until {sw:.1f} s the task alone would lower m, the gain holds dm/dt at "
                          "its floor κ₀w|N∇m|²;\nthen the task raises m by itself and the gain falls to κ₀w (the kink)",
                          fontsize=9.5)
    elif sw is not None:
        axes[2].set_title("null-space method: where shaded the task alone would lower m, the gain holds dm/dt at its "
                          "floor κ₀w|N∇m|²", fontsize=9.5)
    for ax in axes:
        ax.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    if sw is not None:
        handles.append(Patch(**GAIN_BAND, label="null-space gain κ above its floor κ₀w (w: the law's speed / its peak)"))
    axes[0].legend(handles=handles, fontsize=8.5, loc="upper left")
    n = len(meta.get("moving_joints", ())) or "n"
    axes[0].set_title(f"J: the long side's 6 × {n} Jacobian, rows v [m/rad] and ω [rad/rad] (SI)", fontsize=9.5)
    fig.suptitle(f"Manipulability of the long side ({_chain(meta.get('moving_joints', [])) or 'the moving chain'}) while "
                 f"{meta.get('unlocked', 'the boom')} reconfigures\n" + "\n".join(_m_verdict(m, df) for m, df in runs.items()),
                 fontsize=11)
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


def joint_rates(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """Each moving joint's rate, one panel per method (rows) and arm (columns), one colour per joint number,
    with the rate limits and the periods the null-space gain is above its floor. Each panel's peak in its
    title; the verdict against the limits and the joints that turn alike in the figure's title."""
    limits = next(iter(runs.values())).attrs["capmap"]["rate_limits_deg_s"]
    arms = list(dict.fromkeys(_joint_name(c).split(".")[0] for c in limits))
    fig, axes = plt.subplots(len(runs), len(arms), figsize=(6 * len(arms) + 2, 1.2 + 3.4 * len(runs)), sharex=True,
                             sharey=True, squeeze=False)
    top, peaks, sw = 1.15 * max(max(limits.values()), *(df[list(limits)].abs().max().max() for df in runs.values())), [], None
    for row, (method, df) in zip(axes, runs.items()):
        for ax, arm in zip(row, arms):
            sw = _band(ax, df) or sw
            cols = [c for c in limits if _joint_name(c).startswith(arm + ".")]
            for c in cols:
                ax.plot(df.t_s, df[c], lw=1.4, color=f"C{(int(_joint_name(c)[-1]) - 1) % 10}")
            for lim in sorted(set(np.round([limits[c] for c in cols], 9))):
                for sign in (1, -1):
                    ax.axhline(sign * lim, color="0.2", ls=":", lw=1.3)
            c = max(cols, key=lambda c: df[c].abs().max() / limits[c])
            peaks.append((df[c].abs().max() / limits[c], method, _joint_name(c)))
            ax.set(ylim=(-top, top))
            ax.set_title(f"{_name(method)}, {arm}: peak {df[c].abs().max():.3g} deg/s ({_joint_name(c)}, "
                         f"{100 * peaks[-1][0]:.3g} % of its limit)", fontsize=9.5)
            ax.grid(alpha=0.3)
        row[0].set_ylabel("joint rate [deg/s]")
    for ax in axes[-1]:
        ax.set_xlabel("time t [s]")
    numbers = sorted({int(_joint_name(c)[-1]) for c in limits})
    handles = [Line2D([], [], color=f"C{(j - 1) % 10}", lw=1.4, label=f"J{j}") for j in numbers]
    handles.append(Line2D([], [], color="0.2", ls=":", lw=1.3, label="rate limit ±" + ", ".join(
        f"{v:g}" for v in sorted(set(np.round(list(limits.values()), 9)))) + " deg/s"))
    if sw is not None:
        handles.append(Patch(**GAIN_BAND, label="null-space gain above\nits floor κ₀w" + (
            f" (until {sw:.1f} s:\nthe kink)" if np.isfinite(sw) else "")))
    fig.legend(handles=handles, loc="center right", fontsize=9, frameon=False)
    best = {m: max(p for p in peaks if p[1] == m) for m in runs}
    within = max(p[0] for p in peaks) <= 1 + 1e-9
    alike = _alike(runs)
    fig.suptitle(f"Joint rates of the long side, rest to rest: {'within' if within else 'beyond'} the rate limits, peak "
                 + ", ".join(f"{100 * p:.3g} % ({_name(m)}, {j})" for m, (p, _, j) in best.items())
                 + (f"\n{', '.join(alike)} throughout (drawn in each arm's panel)" if alike else ""), fontsize=11)
    save(fig, out_png, rect=(0, 0, 1 - 2.2 / fig.get_figwidth(), 1))


def passive_joint(runs: dict[str, pd.DataFrame], out_png: str | Path) -> None:
    """The unlocked joint's rotation θ and extension d against their ranges: one curve when every run moves it
    alike (the law is prescribed), one per method when a run slowed its time or stopped; the loop-closure
    error of every run against its tolerance in words under the panels."""
    meta = next(iter(runs.values())).attrs["capmap"]
    frames = list(runs.items())
    ref = frames[0][1]
    alike = all(len(df) == len(ref) and np.allclose(df.t_s, ref.t_s) and np.allclose(df.passive_theta_deg,
                ref.passive_theta_deg) and np.allclose(df.passive_d_m, ref.passive_d_m) for _, df in frames)
    shown = frames[:1] if alike else frames
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), sharex=True)
    for ax, key, col, label in ((axes[0], "theta_deg", "passive_theta_deg", "rotation θ [deg]"),
                                (axes[1], "d_m", "passive_d_m", "extension d [m]")):
        for method, df in shown:
            st = {"color": "black", "label": "the law (both methods alike)"} if alike else _style(method)
            ax.plot(df.t_s, df[col], lw=1.8, **st)
        lo, hi = meta["passive_ranges"][key]
        for y in (lo, hi):
            ax.axhline(y, color="tab:red", ls=":", lw=1.3, label="range of the joint" if y == lo else None)
        vals = np.concatenate([df[col].to_numpy() for _, df in shown])
        unit = label.split("[")[1].rstrip("]")
        margin = f"{min(vals.min() - lo, hi - vals.max()):.3g} {unit}"
        ends = " / ".join(f"{df[col].iloc[-1]:.3g}" for _, df in shown)  # one per method when they differ
        ax.set(ylabel=label, xlabel="time t [s]", ylim=(lo - 0.08 * (hi - lo), hi + 0.08 * (hi - lo)))
        ax.set_title(f"{label.split(' [')[0]}: {vals[0]:.3g} → {ends} {unit} in [{lo:g}, {hi:g}], margin ≥ {margin}",
                     fontsize=10)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=9, loc="upper left")
    pos = max(df.closure_pos_err_m.max() for df in runs.values())
    rot = max(df.closure_rot_err_rad.max() for df in runs.values())
    closed = pos <= CLOSURE_TOL and rot <= CLOSURE_TOL
    tol = f"{CLOSURE_TOL:.0e}".replace("e-0", "e-")
    fig.text(0.5, 0.015, f"The closed chain {'stays closed' if closed else 'opens'} in every run: loop-closure error ≤ "
             f"{pos:.2g} m and {rot:.2g} rad (full model, both chains evaluated\nindependently), "
             f"{'within' if closed else 'beyond'} the tolerance of {tol} m and {tol} rad.", ha="center", fontsize=9.5)
    same = ("the same for both methods by construction (prescribed law, neither slowed its time)" if alike
            else "the methods move it differently (a run slowed its time or stopped early: summary.csv)")
    fig.suptitle(f"Passive joint {meta['unlocked']} follows its quintic law within its ranges,\n{same}", fontsize=11)
    save(fig, out_png, rect=(0, 0.08, 1, 1))


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
BOOM, CAPTURE, IDLE, PLATFORM = 0xE0A030, 0x8A3FC0, 0x9A9A9A, 0x707070


def animation(motion: ReconfigMotion, segments: list[tuple[str, np.ndarray, np.ndarray]], title: str,
              out_html: str | Path) -> None:
    """The robot as cylinders on its links (``segments``: link, a, b in the link frame) moved by ``motion``: the
    links both runs move alike drawn once, the first run opaque, any other as a translucent sheath around it (it
    shows where the runs coincide), the boom the unlocked joint moves orange, the capture a cube, the arms outside
    the loop grey, the platform a disc. Over the view: ``title`` (its first line; the others under it), a legend,
    and as it plays the simulated time and each run's manipulability (and how far apart the runs are)."""
    runs, links, (held, _) = list(motion.poses), motion.links, motion.capture
    first = motion.poses[runs[0]]
    shared = {link for i, link in enumerate(links)
              if all(p.shape == first.shape and np.allclose(p[:, i], first[:, i]) for p in motion.poses.values())}
    loop = {link.split(".")[0] for link in motion.capture}
    idle = sorted({link.split(".")[0] for link, _, _ in segments} - loop)
    secs = {r: (len(p) - 1) / motion.fps for r, p in motion.poses.items()}
    legend = [(RUN_COLOUR.get(r, 0x808080), 1.0 if r == runs[0] else 0.3, f"{RUN_NAME.get(r, r)} run, {secs[r]:.1f} s"
               + (": the arms in the loop" if r == runs[0] else ": a translucent sheath (around the blue arm where the "
                  "runs coincide)")) for r in runs]
    legend += [(BOOM, 1.0, f"boom moved by the unlocked joint {motion.unlocked}"),
               (CAPTURE, 1.0, f"capture: {' held by '.join(motion.capture)}, closing the loop")]
    legend += [(IDLE, 1.0, f"{', '.join(idle)}: not in the loop, still")] if idle else []
    legend += [(PLATFORM, 1.0, "platform")]
    head, *lines = title.split("\n")
    vis = new_scene(head, lines=tuple(lines), legend=tuple(legend), fps=motion.fps,
                    frame_text=_readout(motion, [i for i, link in enumerate(links) if link not in shared]))
    layers = [("shared", first, shared)] + [(r, motion.poses[r], set(links) - shared) for r in runs]
    for root, _, mine in layers:
        sheath = root not in ("shared", runs[0])
        look = {"opacity": 0.3 if sheath else 1.0, "colour": RUN_COLOUR.get(runs[0] if root == "shared" else root)}
        for k, (link, a, b) in enumerate(segments):
            if link in mine:
                colour = BOOM if link == motion.unlocked else IDLE if link.split(".")[0] in idle else look["colour"]
                geom, pose = cylinder(a, b, (0.06 if link == motion.unlocked else 0.08) * (1.5 if sheath else 1.0))
                vis[f"{root}/{link}/piece{k}"].set_object(geom, material(colour, look["opacity"]))
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
    ends = [(links.index(link), e) for link, a, b in segments for e in (a, b)]
    pts = np.array([T[i, :3, :3] @ e + T[i, :3, 3] for p in motion.poses.values() for T in p[::10] for i, e in ends])
    hide_helpers(vis)  # a space robot: no floor
    aim(vis, (*runs, "shared", "platform"), (pts.min(axis=0) + pts.max(axis=0)) / 2,
        0.36 * np.linalg.norm(np.ptp(pts, axis=0)) * np.array([1.0, -1.0, 0.55]), right=0.12)
    write_html(vis, out_html)


def _readout(motion: ReconfigMotion, moving: list[int]) -> tuple[str, ...]:
    """Per frame: each run's manipulability m (and its change since the capture) and, with two runs, how far apart
    their ``moving`` links are."""
    texts = []
    for f in range(max(len(p) for p in motion.poses.values())):
        m = {r: v[min(f, len(v) - 1)] for r, v in motion.m.items()}
        words = ", ".join(f"{RUN_NAME.get(r, r)} {x:.1f} ({round(100 * (x / motion.m[r][0] - 1)):+d} %)" for r, x in m.items())
        at = [p[min(f, len(p) - 1), moving, :3, 3] for p in motion.poses.values()]
        apart = np.linalg.norm(at[0] - at[1], axis=1).max() if len(at) == 2 and moving else None
        gap = "" if apart is None else f"; the runs' joints up to {apart:.2f} m apart"
        texts.append(f"manipulability m: {words}{gap}")
    return tuple(texts)
