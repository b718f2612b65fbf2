"""What one plan/verify job is given besides the run's fields: a task at one payload (light: no
numerics imports, so that every stage can rebuild it without depending on a family's code)."""

from __future__ import annotations

from dataclasses import dataclass, field

from capmap.config.typed import ROUND

__all__ = ["PlanTask", "payload_label"]


def payload_label(payload_kg: float) -> str:
    """File-name label of a payload: 1500 -> '1500', 1250.5 -> '1250.5'."""
    return f"{float(payload_kg):g}"


@dataclass(frozen=True)
class PlanTask:
    """One plan/verify job: the main task at one of its payloads (``name`` None; start and start
    configuration resolved, see :mod:`capmap.config.failure`) or a further task of ``tasks``."""

    payload_kg: float
    start_m: tuple[float, float, float] = field(metadata=ROUND)
    goal_m: tuple[float, float, float]
    q_start_deg: tuple[float, ...] = field(metadata=ROUND)
    name: str | None = None

    @classmethod
    def from_doc(cls, d: dict) -> "PlanTask":
        return cls(payload_kg=float(d["payload_kg"]), start_m=tuple(d["start_m"]), goal_m=tuple(d["goal_m"]),
                   q_start_deg=tuple(d["q_start_deg"]), name=d["name"])
