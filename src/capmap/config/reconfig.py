"""Config section of the reconfigurable-robot family: ``reconfig`` (its problem: :mod:`capmap.reconfig.build`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from capmap.config.typed import FILE, as_tuple

__all__ = ["ReconfigConfig"]


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
