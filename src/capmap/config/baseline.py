"""Config section of the healthy-arm baseline: ``baseline`` (optional; absent: these defaults)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BaselineConfig"]


@dataclass(frozen=True)
class BaselineConfig:
    """``baseline``: the failed joint's angles are swept in steps of ``step_deg`` (through the failed
    angle); ``screen_directions`` of a finite direction set bound each (angle, solution) before the full
    set (the whole sphere: every candidate evaluated; :func:`capmap.capacity.baseline.healthy_capacity`);
    each point's best posture on that grid is
    followed ``polish_levels`` levels between grid angles (from half the step, halving it);
    ``check_voxels`` voxels' worst points are evaluated again on a grid of ``check_step_deg`` (the
    shortfall against it shown)."""

    step_deg: float = 10.0
    screen_directions: int = 48
    polish_levels: int = 5
    check_voxels: int = 200
    check_step_deg: float = 1.0

    @classmethod
    def from_doc(cls, d: dict | None) -> "BaselineConfig":
        return cls(**(d or {}))
