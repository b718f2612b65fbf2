"""The reconfiguration family's one meeting of configuration and numerics: the ``reconfig`` section
(:class:`capmap.config.reconfig.ReconfigConfig`) in, the family's problem out: the platform loaded, the
capture and unlocked joint checked, the capture configuration, the law, the joint-rate limits, with
errors naming the config keys. The pre-run checks (:mod:`capmap.checks`) and the stages call these."""

from __future__ import annotations

import numpy as np

from capmap.config.reconfig import ReconfigConfig
from capmap.config.typed import per_item
from capmap.errors import CapmapError, ConfigError
from capmap.reconfig.law import QuinticLaw
from capmap.reconfig.multiarm import PlatformDescription, PlatformState
from capmap.reconfig.planner import PlannerSettings
from capmap.reconfig.platform_file import load_platform
from capmap.reconfig.problem import ReconfigProblem, build_problem

__all__ = ["law_of", "platform_state", "reconfig_problem", "rate_limits", "planner_settings"]


def law_of(cfg: ReconfigConfig) -> QuinticLaw:
    """The motion law of ``reconfig.law``, from the locked values (0, 0) to (theta, d)."""
    return QuinticLaw(0.0, float(np.deg2rad(cfg.theta_deg)), 0.0, float(cfg.d_m), float(cfg.duration_s))


def platform_state(desc: PlatformDescription, configuration_deg: dict[str, tuple[float, ...]]) -> PlatformState:
    """Revolute joint angles (rad) of every arm from ``reconfig.configuration_deg`` (checked)."""
    missing = [a.name for a in desc.arms if a.name not in configuration_deg]
    extra = sorted(set(configuration_deg) - {a.name for a in desc.arms})
    if missing or extra:
        raise ConfigError(f"reconfig.configuration_deg: {'missing arm ' + missing[0] if missing else 'unknown arm ' + extra[0]}"
                          f" ({desc.name} has arms {', '.join(a.name for a in desc.arms)})")
    q = {}
    for arm in desc.arms:
        values = configuration_deg[arm.name]
        if len(values) != len(arm.revolute):
            raise ConfigError(f"reconfig.configuration_deg.{arm.name} has {len(values)} values but {arm.name} has "
                              f"{len(arm.revolute)} revolute joints ({', '.join(arm.revolute)})")
        for name, v in zip(arm.revolute, values):
            lo, hi = np.rad2deg(desc.joint(name).range_rad)
            if not lo <= v <= hi:
                raise ConfigError(f"reconfig.configuration_deg.{arm.name}: {name} = {v:g} deg is outside its range "
                                  f"[{lo:g}, {hi:g}] deg")
            q[name] = float(np.deg2rad(v))
    return PlatformState(q)


def reconfig_problem(cfg: ReconfigConfig) -> ReconfigProblem:
    """Load the robot and put the problem together, with errors naming the config keys."""
    desc = load_platform(cfg.robot)
    for key, check in (("capture", lambda: desc.capture(cfg.capture)), ("unlock", lambda: desc.joint(cfg.unlock))):
        try:
            check()
        except CapmapError as exc:
            raise ConfigError(f"reconfig.{key} = {getattr(cfg, key)!r}: {exc}") from None
    state = platform_state(desc, cfg.configuration_deg)
    try:
        return build_problem(desc, cfg.capture, cfg.unlock, state, law_of(cfg))
    except CapmapError as exc:
        raise ConfigError(f"reconfig: {exc.in_terms(law='reconfig.law', configuration='reconfig.configuration_deg')}"
                          ) from None


def rate_limits(cfg: ReconfigConfig, problem: ReconfigProblem) -> np.ndarray:
    """``reconfig.joint_rate_limit_deg_s`` per joint of the moving side, rad/s."""
    return np.deg2rad(per_item(cfg.joint_rate_limit_deg_s, problem.split.moving.dof, "reconfig.joint_rate_limit_deg_s"))


def planner_settings(cfg: ReconfigConfig, problem: ReconfigProblem, method: str) -> PlannerSettings:
    """The planner's settings of ``method`` (nullspace: ``reconfig.kappa0``; pinv: no null-space gain)."""
    kappa0 = cfg.kappa0 if method == "nullspace" else 0.0
    return problem.settings(method, cfg.dt_s, kappa0, rate_limits(cfg, problem), cfg.min_time_scale)
