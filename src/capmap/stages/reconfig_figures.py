"""Figures and animation of the reconfiguration (kept apart so that the planner jobs do not import
matplotlib)."""

from __future__ import annotations

import numpy as np

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.reconfig import ReconfigMotion, animation, joint_rates, manipulability, passive_joint
from capmap.reconfig.build import reconfig_problem
from capmap.reconfig.law import QuinticLaw
from capmap.reconfig.multiarm import link_segments, platform_model
from capmap.reconfig.tables import column
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_reconfig_plots", "stage_reconfig_animation"]


def _with_gain_floor(df):
    """The run's table with the null-space gain's floor kappa0 w(u) beside its gain (``kappa_floor``; w: the law's
    speed over its peak at the law phase u), when the run's configuration states kappa0: where the gain is above
    it, the task alone would lower m."""
    kappa0 = df.attrs["capmap"].get("config", {}).get("run", {}).get("reconfig", {}).get("kappa0")
    if kappa0 and "law_phase" in df:
        df["kappa_floor"] = kappa0 * QuinticLaw(0.0, 0.0, 0.0, 0.0, 1.0).speed_weight(df.law_phase.to_numpy())
    return df


def stage_reconfig_plots(tables: list[str], out: Outputs) -> None:
    """m(t), the smallest singular value and dm/dt of both methods; joint rates; the passive joint."""
    runs = {df.attrs["capmap"]["method"]: _with_gain_floor(df) for df in map(datasets.read, tables)}
    manipulability(runs, out["manipulability"])
    joint_rates(runs, out["rates"])
    passive_joint(runs, out["passive"])
    stage_logger(__name__, "reconfig plots").info(f"-> {', '.join(out.values())}")


def stage_reconfig_animation(tables: list[str], out_html: str, slice_json: str) -> None:
    """MeshCat static HTML: the robot during the null-space reconfiguration (the pseudo-inverse's
    motion as a translucent sheath), sampled at ``reconfig.animation_fps`` frames per second, with each run's
    manipulability as it plays."""
    cfg = stage_config(slice_json).run.reconfig
    problem = reconfig_problem(cfg)
    model = platform_model(problem.description)
    segments = link_segments(problem.description)
    capture = problem.description.capture(cfg.capture)
    links = tuple(sorted({s[0] for s in segments} | {capture.link_a, capture.link_b}))
    frames, m, names, change = {}, {}, {"nullspace": "null\u2011space", "pinv": "pseudo\u2011inverse"}, []
    for df in map(datasets.read, tables):
        meta = df.attrs["capmap"]
        s = meta.get("summary", {})
        if "m_change_pct" in s:  # the verdict: each method's change of the manipulability
            change.append((names.get(meta["method"], meta["method"]), f"{s['m_change_pct']:+.0f} %".replace("-", "−")))
        t = np.arange(0.0, df.t_s.iloc[-1] + 1e-9, 1.0 / cfg.animation_fps)
        sub = df.iloc[np.clip(np.searchsorted(df.t_s.to_numpy(), t), 0, len(df) - 1)]
        joints = problem.split.moving.joints
        states = [problem.state.with_values(joints, np.deg2rad([r[f"q_{column(j)}_deg"] for j in joints]))
                  .with_passive(problem.split.unlocked, np.deg2rad(r.passive_theta_deg), r.passive_d_m)
                  for _, r in sub.iterrows()]
        frames[meta["method"]] = np.array([model.placements(s, links) for s in states])
        m[meta["method"]] = sub.manipulability.to_numpy()
    unlocked, robot = problem.split.unlocked, f"Reconfigurable {len(problem.description.arms)}-arm robot"
    title = f"{robot}: manipulability " + " vs ".join(f"{c} ({n})" for n, c in change) if change else robot
    animation(ReconfigMotion(links, frames, m, cfg.animation_fps, unlocked, (capture.link_a, capture.link_b)),
              segments, title, out_html)
    stage_logger(__name__, "reconfig animation").info(f"{len(next(iter(frames.values())))} frames -> {out_html}")
