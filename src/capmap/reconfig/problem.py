"""A reconfiguration problem put together: the robot, the closed capture configuration, the
split loop and the law; and the whole robot's state along a planned motion, with the loop
closure evaluated independently by the full Pinocchio model of the robot."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.core.kinematics import pose_error
from capmap.errors import CapmapError
from capmap.reconfig.law import QuinticLaw
from capmap.reconfig.loop import LoopSplit, close_capture, split_loop
from capmap.reconfig.multiarm import PlatformDescription, PlatformModel, PlatformState
from capmap.reconfig.planner import PlannerSettings, Reconfiguration

__all__ = ["ReconfigProblem", "build_problem", "states_along", "closure_errors", "RunSummary", "summarise"]


@dataclass(frozen=True)
class ReconfigProblem:
    """description; state: every joint at the law's start, the capture closed exactly; split: the
    loop cut at the unlocked joint; fixed_end (4, 4): the short side's end frame; law;
    correction_rad: the change IK made to the unlocked joint's arm to close the capture."""

    description: PlatformDescription
    state: PlatformState
    split: LoopSplit
    fixed_end: np.ndarray
    law: QuinticLaw
    correction_rad: np.ndarray

    @property
    def q0(self) -> np.ndarray:
        return self.split.moving.values(self.state)

    def settings(self, method: str, dt_s: float, kappa0: float, rate_limit: np.ndarray,
                 min_time_scale: float) -> PlannerSettings:
        """Planner settings with the moving side's joint ranges from the robot file."""
        ranges = np.array([self.description.joint(j).range_rad for j in self.split.moving.joints])
        return PlannerSettings(method, dt_s, kappa0, np.asarray(rate_limit, dtype=float), ranges[:, 0], ranges[:, 1],
                               min_time_scale)


def build_problem(desc: PlatformDescription, capture: str, unlock: str, state: PlatformState,
                  law: QuinticLaw) -> ReconfigProblem:
    """Close the capture by IK of the unlocked joint's arm (from the given angles), cut the loop at
    ``unlock`` and check the law against the joint's ranges. Errors name their inputs by role
    (``law``, ``configuration``)."""
    joint = desc.joint(unlock)
    if not joint.passive:
        raise CapmapError(f"{unlock} is a {joint.kind} joint, not a passive one that can be unlocked")
    for name, values, rng, unit in (("theta", (law.theta0, law.theta1), joint.range_rad, "deg"),
                                    ("d", (law.d0, law.d1), joint.range_m, "m")):
        scale = np.rad2deg(1.0) if unit == "deg" else 1.0
        for v in values:
            if not rng[0] <= v <= rng[1]:
                raise CapmapError(f"{{law}} takes {unlock}'s {name} to {v * scale:g} {unit}, outside its range "
                                  f"[{rng[0] * scale:g}, {rng[1] * scale:g}] {unit}", law="the law")
    start = state.with_passive(unlock, law.theta0, law.d0)
    split = split_loop(desc, capture, unlock, start)  # (the split's fixed transforms do not change with closing)
    closed, correction = close_capture(desc, capture, desc.arm_of(unlock).name, start)
    fixed_end = split.fixed.chain.fk(split.fixed.values(closed)[None])[0]
    return ReconfigProblem(desc, closed, split, fixed_end, law, correction)


def states_along(problem: ReconfigProblem, run: Reconfiguration) -> list[PlatformState]:
    """The whole robot's state at every recorded step of a run."""
    names = problem.split.moving.joints
    return [problem.state.with_values(names, q).with_passive(problem.split.unlocked, th, d)
            for q, th, d in zip(run.q, run.theta, run.d)]


def closure_errors(problem: ReconfigProblem, model: PlatformModel, run: Reconfiguration) -> np.ndarray:
    """Pose error (K, 6) of the capture at every step, from the full Pinocchio model of the robot
    with every joint at its value (both chains of the loop evaluated independently of the
    split's chains)."""
    cap = problem.description.capture(problem.split.capture)
    links = (cap.link_a, cap.link_b)
    poses = np.array([model.placements(s, links) for s in states_along(problem, run)])
    return pose_error(poses[:, 0], poses[:, 1] @ cap.transform)


@dataclass(frozen=True)
class RunSummary:
    """What a run achieved: status; duration (s) and steps; m at the start, its minimum (and when)
    and at the end, the change in %; the smallest singular value of J; how many steps had
    dm/dt < -tol (tol = 1e-9 |dm/dt| scale) and the most negative dm/dt; the largest loop
    closure error of the full model and task error of the long side; the largest joint rate
    (deg/s) and its share of the limit; the smallest margin to a joint range (deg); the
    slowest time scale; the largest joint rate at the end (rest to rest)."""

    status: str
    duration_s: float
    steps: int
    m_initial: float
    m_min: float
    t_m_min_s: float
    m_final: float
    m_change_pct: float
    min_singular_value: float
    steps_dm_dt_negative: int
    min_dm_dt: float
    max_closure_pos_err_m: float
    max_closure_rot_err_rad: float
    max_task_pos_err_m: float
    max_task_rot_err_rad: float
    max_joint_rate_deg_s: float
    peak_rate_joint: str
    max_rate_pct_of_limit: float
    min_range_margin_deg: float
    min_time_scale: float
    final_joint_rate_deg_s: float


def summarise(run: Reconfiguration, closure: np.ndarray, settings: PlannerSettings,
              joints: tuple[str, ...]) -> RunSummary:
    """The summary of a run (see :class:`RunSummary`); closure (K, 6) from :func:`closure_errors`."""
    k_min = int(np.argmin(run.m))
    tol = 1e-9 * max(1.0, float(np.abs(run.dm_dt).max()))
    rates = np.abs(run.qd)
    peak = np.unravel_index(int(np.argmax(rates)), rates.shape)
    margin = np.minimum(run.q - settings.q_lower, settings.q_upper - run.q)
    return RunSummary(
        status=run.status, duration_s=float(run.t_s[-1]), steps=run.steps, m_initial=float(run.m[0]),
        m_min=float(run.m[k_min]), t_m_min_s=float(run.t_s[k_min]), m_final=float(run.m[-1]),
        m_change_pct=float(100 * (run.m[-1] - run.m[0]) / run.m[0]),
        min_singular_value=float(run.min_singular_value.min()),
        steps_dm_dt_negative=int((run.dm_dt < -tol).sum()), min_dm_dt=float(run.dm_dt.min()),
        max_closure_pos_err_m=float(np.linalg.norm(closure[:, :3], axis=1).max()),
        max_closure_rot_err_rad=float(np.linalg.norm(closure[:, 3:], axis=1).max()),
        max_task_pos_err_m=float(np.linalg.norm(run.task_error[:, :3], axis=1).max()),
        max_task_rot_err_rad=float(np.linalg.norm(run.task_error[:, 3:], axis=1).max()),
        max_joint_rate_deg_s=float(np.rad2deg(rates.max())), peak_rate_joint=joints[peak[1]],
        max_rate_pct_of_limit=float(100 * (rates / settings.rate_limit).max()),
        min_range_margin_deg=float(np.rad2deg(margin.min())), min_time_scale=float(run.time_scale.min()),
        final_joint_rate_deg_s=float(np.rad2deg(rates[-1].max())))
