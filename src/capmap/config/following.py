"""Config section of the following family: ``follow`` (control period, the space and ground cases)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from capmap.config.typed import FILE, as_tuple

__all__ = ["SpaceFollowConfig", "GroundFollowConfig", "FollowConfig", "STORE_PERIOD_S"]

STORE_PERIOD_S = 0.01  # s: the stored time series' period when follow.store_period_s is not given


@dataclass(frozen=True)
class SpaceFollowConfig:
    """``follow.space``: the space arm follows its verified path at ``payload_kg`` (one of
    task.payload_kg) under a torque limit, with an S-curve of jerk j_max (v, a from task)."""

    payload_kg: float
    joint_torque_nm: float | tuple[float, ...]
    j_max_mps3: float
    catch_up_hz: float


@dataclass(frozen=True)
class GroundFollowConfig:
    """``follow.ground``: a ground arm follows a straight line from FK(q_start) by line_m."""

    robot: str = field(metadata=FILE)
    q_start_deg: tuple[float, ...]
    line_m: tuple[float, float, float]
    payload_kg: float
    v_max_mps: float
    a_max_mps2: float
    j_max_mps3: float
    joint_torque_nm: float | tuple[float, ...]
    catch_up_hz: float


@dataclass(frozen=True)
class FollowConfig:
    """``follow``: the control period, the stored time series' period (every control period when
    equal to it) and the configured cases (None when absent)."""

    period_s: float
    space: SpaceFollowConfig | None = None
    ground: GroundFollowConfig | None = None
    store_period_s: float | None = None  # follow.store_period_s; None: STORE_PERIOD_S, or the control period if longer

    @classmethod
    def from_doc(cls, d: dict) -> "FollowConfig":
        space = SpaceFollowConfig(**{k: as_tuple(v) for k, v in d["space"].items()}) if "space" in d else None
        ground = GroundFollowConfig(**{k: as_tuple(v) for k, v in d["ground"].items()}) if "ground" in d else None
        return cls(period_s=d["period_s"], space=space, ground=ground,
                   **{k: d[k] for k in ("store_period_s",) if k in d})

    @property
    def store_every(self) -> int:
        """Control periods per stored row of the time series (>= 1): the most whole periods within the
        store period (rows never farther apart than asked)."""
        store = max(STORE_PERIOD_S, self.period_s) if self.store_period_s is None else self.store_period_s
        return max(1, int(np.floor(store / self.period_s * (1 + 1e-9))))

    @property
    def cases(self) -> tuple[str, ...]:
        return tuple(c for c in ("space", "ground") if getattr(self, c) is not None)
