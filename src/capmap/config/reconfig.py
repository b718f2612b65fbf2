"""Config section of the reconfigurable-robot family: ``reconfig``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from capmap.config.platform_file import load_platform
from capmap.config.typed import FILE
from capmap.config.validation import as_tuple, per_item
from capmap.errors import CapmapError, ConfigError
from capmap.reconfig.law import QuinticLaw
from capmap.reconfig.multiarm import PlatformDescription, PlatformState
from capmap.reconfig.problem import ReconfigProblem, build_problem

__all__ = ["ReconfigConfig", "platform_state", "reconfig_problem", "rate_limits"]


@dataclass(frozen=True)
class ReconfigConfig:
    """``reconfig``: the platform robot file, the capture and the unlocked joint, the capture
    configuration (deg, per arm), the law (theta_deg, d_m, duration_s), the RK4 step, the
    null-space gain, the joint-rate limit(s) and the slowest time scale allowed."""

    robot: str = field(metadata=FILE)
    capture: str
    unlock: str
    configuration_deg: dict[str, tuple[float, ...]]
    theta_deg: float
    d_m: float
    duration_s: float
    dt_s: float
    kappa0: float
    joint_rate_limit_deg_s: float | tuple[float, ...]
    min_time_scale: float = 0.05  # the defaults of reconfig.min_time_scale and reconfig.animation_fps
    animation_fps: float = 5.0

    @classmethod
    def from_doc(cls, d: dict) -> "ReconfigConfig":
        law = d["law"]
        return cls(robot=d["robot"], capture=d["capture"], unlock=d["unlock"],
                   configuration_deg={arm: tuple(v) for arm, v in d["configuration_deg"].items()},
                   theta_deg=law["theta_deg"], d_m=law["d_m"], duration_s=law["duration_s"], dt_s=d["dt_s"],
                   joint_rate_limit_deg_s=as_tuple(d["joint_rate_limit_deg_s"]),
                   **{k: d[k] for k in ("kappa0", "min_time_scale", "animation_fps") if k in d})  # else the defaults

    def law(self) -> QuinticLaw:
        """The motion law, from the locked values (0, 0) to (theta, d)."""
        return QuinticLaw(0.0, float(np.deg2rad(self.theta_deg)), 0.0, float(self.d_m), float(self.duration_s))


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
        return build_problem(desc, cfg.capture, cfg.unlock, state, cfg.law())
    except CapmapError as exc:
        raise ConfigError(f"reconfig: {exc.in_terms(law='reconfig.law', configuration='reconfig.configuration_deg')}"
                          ) from None


def rate_limits(cfg: ReconfigConfig, problem: ReconfigProblem) -> np.ndarray:
    """``reconfig.joint_rate_limit_deg_s`` per joint of the moving side, rad/s."""
    return np.deg2rad(per_item(cfg.joint_rate_limit_deg_s, problem.split.moving.dof, "reconfig.joint_rate_limit_deg_s"))
