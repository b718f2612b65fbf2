"""The healthy arm's problem from the run's config: the capacity family's second meeting of configuration
and numerics (:mod:`capmap.capacity.build` is the map's), kept apart so that the map's stages, whose code
fingerprints follow their imports, do not depend on the healthy arm's search
(:mod:`capmap.capacity.self_motion` and what it uses)."""

from __future__ import annotations

import numpy as np

from capmap.capacity.build import capacity_problem, load_limits
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.self_motion import HealthyProblem, SelfMotion, screening_subset, self_motion_angles
from capmap.config.run import RunConfig
from capmap.robots import locked_arm

__all__ = ["healthy_problem"]


def healthy_problem(run: RunConfig, problem: CapacityProblem | None = None, reference: bool = False) -> HealthyProblem:
    """The run's healthy arm (``baseline``): its failed joint swept through the failed angle
    ``baseline.step_deg`` apart, each point's best posture followed ``baseline.polish_levels`` levels
    between them (``reference``: the check's sweep instead, ``baseline.check_step_deg`` apart, not
    followed), the arm held at each angle, the run's problem (``problem``: already built) and
    ``baseline.screen_directions`` of its directions as the screening set."""
    problem = capacity_problem(run) if problem is None else problem
    robot, j = problem.arm.robot, run.failure.joint
    lo, hi = np.rad2deg(robot.q_lower[j - 1]), np.rad2deg(robot.q_upper[j - 1])
    bl = run.baseline
    step_deg, polish_levels = (bl.check_step_deg, 0) if reference else (bl.step_deg, bl.polish_levels)
    sm = SelfMotion.build(self_motion_angles(lo, hi, run.failure.angle_deg, step_deg),
                          lambda a: locked_arm(robot, j, a), load_limits(run.limits, robot.n_joints).for_arm, lo, hi)
    return HealthyProblem(problem, sm, screening_subset(problem.directions, bl.screen_directions),
                          polish_levels)
