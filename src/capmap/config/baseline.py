"""Config section of the healthy-arm baseline: ``baseline`` (optional; absent: these defaults)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BaselineConfig"]


@dataclass(frozen=True)
class BaselineConfig:
    """``baseline``: the failed joint's angles are swept in steps of ``step_deg`` (through the failed
    angle); ``screen_directions`` of the direction set bound each (angle, solution) before the full set
    (:func:`capmap.capacity.baseline.healthy_capacity`); ``check_voxels`` voxels' worst points are
    evaluated again at half and a quarter of the step (the convergence shown)."""

    step_deg: float = 10.0
    screen_directions: int = 48
    check_voxels: int = 200

    @classmethod
    def from_doc(cls, d: dict | None) -> "BaselineConfig":
        return cls(**(d or {}))
