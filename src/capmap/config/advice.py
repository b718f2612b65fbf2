"""Config section of the lock-angle advice: ``advice`` (optional; absent: these defaults).

The advice sweeps a joint's lock angle and verifies the run's tasks at each angle on the arm locked
there; the failure-tolerant map takes the minimum over every joint's sweep. Its maps have the fault
atlas' sampling and voxel edge (``atlas.sampling``, ``atlas.edge_m``) and the run's directions: without an
atlas section there is no advice (the ``advise`` target and ``capmap advise`` say so in one line)."""

from __future__ import annotations

from dataclasses import dataclass

from capmap.errors import ConfigError

__all__ = ["AdviceConfig"]


@dataclass(frozen=True)
class AdviceConfig:
    """``advice``: the joints to advise on (``joints``; None: the failed one, ``lock.joint``), each
    swept in steps of ``step_deg`` through the angle it stood at (``task.q_ini_deg``), one turn at most
    (a joint turning less: its whole range)."""

    joints: tuple[int, ...] | None = None
    step_deg: float = 10.0

    @classmethod
    def from_doc(cls, d: dict | None) -> "AdviceConfig":
        d = dict(d or {})
        if "joints" in d:
            d["joints"] = tuple(int(j) for j in d["joints"])
        return cls(**d)

    def joints_of(self, failed_joint: int) -> tuple[int, ...]:
        """The joints advised on: the listed ones, else the failed joint."""
        return self.joints if self.joints is not None else (int(failed_joint),)

    def check(self, robot: str, n_joints: int, failed_joint: int, source: str = "config") -> None:
        """Every joint the advice is on exists on ``robot``."""
        for j in self.joints_of(failed_joint):
            if not 1 <= j <= n_joints:
                raise ConfigError(f"{source}: advice.joints: joint {j} is out of range: {robot} has joints "
                                  f"1..{n_joints}")
