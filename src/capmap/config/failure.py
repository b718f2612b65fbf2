"""The failure in one edit: from ``lock`` and ``task`` to the locked arm's start.

``task.q_ini_deg`` is the configuration when the joint failed and ``lock.joint`` the failed
joint. By default the joint is locked where it stood (``lock.angle_deg`` = its q_ini) and
the task starts where the end effector stood (``task.start_m`` = FK(q_ini)). The start
configuration is the IK branch of the locked arm at the start pose (``task.start_m``,
``task.orientation_rpy_deg``) nearest to q_ini:

- lock angle = q_ini's: q_ini itself up to rounding (a q_ini typed to whole degrees is a
  few tenths of a degree from its branch);
- an explicit lock angle that differs ("what if it had locked at ..."): the nearest branch,
  however far.

Either way the choice is reported (which branch, how far from q_ini, and how far q_ini's own
end effector is from the start pose when that is more than 1 mm or 0.5 deg), never refused:
a q_ini that only roughly matches the start still names a branch. An unreachable start is
an error naming the key. The resolution itself (it needs the robot and its IK) is
:func:`capmap.capacity.build.resolve_failure`; this module holds its result.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from capmap.config.capacity import TaskConfig
from capmap.config.jobs import PlanTask
from capmap.config.typed import ROUND

__all__ = ["Failure", "main_task"]


@dataclass(frozen=True)
class Failure:
    """The resolved failure: locked joint (1-based) and angle, start position, start configuration
    (every joint, deg; the locked one at ``angle_deg``), and which IK branch it is."""

    joint: int
    angle_deg: float = field(metadata=ROUND)  # rounded in slices (1e-9): equal failures give equal slices
    start_m: tuple[float, float, float] = field(metadata=ROUND)
    q_start_deg: tuple[float, ...] = field(metadata=ROUND)
    branch: int  # index among the n_branches solutions at the start (ik.solve order)
    n_branches: int
    offset_deg: float  # largest |q_start - q_ini| over the joints that still move
    angle_given: bool
    start_given: bool
    ini_miss_m: float = 0.0  # how far q_ini's end effector is from the start position
    ini_miss_deg: float = 0.0  # and from the task orientation

    def describe(self) -> str:
        """One line for the log: what was resolved and from where."""
        angle = "lock.angle_deg" if self.angle_given else "where it stood (task.q_ini_deg)"
        start = "task.start_m" if self.start_given else "FK(task.q_ini_deg)"
        miss = (f" (at q_ini the end effector is {self.ini_miss_m:.3g} m from the start and {self.ini_miss_deg:.2f} "
                "deg from task.orientation_rpy_deg)" if self.ini_miss_m > 1e-3 or self.ini_miss_deg > 0.5 else "")
        return (f"joint {self.joint} locked at {self.angle_deg:g} deg ({angle}); start "
                f"[{', '.join(f'{v:.4f}' for v in self.start_m)}] m ({start}); start configuration = IK branch "
                f"{self.branch + 1} of {self.n_branches}, {self.offset_deg:.2f} deg from task.q_ini_deg{miss}")


def main_task(task: TaskConfig, failure: Failure, payload_kg: float) -> PlanTask:
    """The plan/verify job of the main task at one of its payloads: the resolved start and start
    configuration, the task's goal."""
    return PlanTask(payload_kg=float(payload_kg), start_m=failure.start_m, goal_m=task.goal_m,
                    q_start_deg=failure.q_start_deg)
