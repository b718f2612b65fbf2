"""Figures and animation of the reconfiguration (kept apart so that the planner jobs do not import
matplotlib)."""

from __future__ import annotations

import numpy as np

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.reconfig import animation, joint_rates, manipulability, passive_joint
from capmap.reconfig.build import reconfig_problem
from capmap.reconfig.multiarm import link_segments, platform_model
from capmap.reconfig.tables import column
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_reconfig_plots", "stage_reconfig_animation"]


def stage_reconfig_plots(tables: list[str], out: Outputs) -> None:
    """m(t), the smallest singular value and dm/dt of both methods; joint rates; the passive joint."""
    runs = {df.attrs["capmap"]["method"]: df for df in map(datasets.read, tables)}
    manipulability(runs, out["manipulability"])
    joint_rates(runs, out["rates"])
    passive_joint(runs, out["passive"])
    stage_logger(__name__, "reconfig plots").info(f"-> {', '.join(out.values())}")


def stage_reconfig_animation(tables: list[str], out_html: str, slice_json: str) -> None:
    """MeshCat static HTML: the robot during the null-space reconfiguration (the pseudo-inverse's
    motion as a translucent ghost), sampled at ``reconfig.animation_fps`` frames per second."""
    cfg = stage_config(slice_json).run.reconfig
    problem = reconfig_problem(cfg)
    model = platform_model(problem.description)
    segments = link_segments(problem.description)
    links = tuple(sorted({s[0] for s in segments}))
    frames, words = {}, []
    for df in map(datasets.read, tables):
        meta = df.attrs["capmap"]
        m = meta.get("summary", {})
        if "m_final" in m:  # the verdict of each method, over the view
            name = {"nullspace": "null-space", "pinv": "pseudo-inverse"}.get(meta["method"], meta["method"])
            words.append(f"{name}: manipulability m {m['m_initial']:.1f} → {m['m_final']:.1f} ({m['m_change_pct']:+.0f} %)")
        t = np.arange(0.0, df.t_s.iloc[-1] + 1e-9, 1.0 / cfg.animation_fps)
        rows = np.clip(np.searchsorted(df.t_s.to_numpy(), t), 0, len(df) - 1)
        sub = df.iloc[rows]
        names = problem.split.moving.joints
        states = [problem.state.with_values(names, np.deg2rad([r[f"q_{column(j)}_deg"] for j in names]))
                  .with_passive(problem.split.unlocked, np.deg2rad(r.passive_theta_deg), r.passive_d_m)
                  for _, r in sub.iterrows()]
        frames[meta["method"]] = np.array([model.placements(s, links) for s in states])
    animation(links, segments, frames, cfg.animation_fps, problem.split.unlocked,
              f"{problem.description.name}: reconfiguration with {problem.split.unlocked} unlocked"
              + "".join(f"\n{w}" for w in words), out_html)
    stage_logger(__name__, "reconfig animation").info(f"{len(next(iter(frames.values())))} frames -> {out_html}")
