"""A dual-arm job's motion planned around the space no camera observed: the unknown boxes near the warm
start go to the optimiser, and after each solve the motion (finer grid) is checked against every unknown
voxel and the boxes near it join, up to three solves. Numerics only: the config's sections arrive as
settings (:mod:`capmap.dualarm.build`), the datasets as arrays."""

from __future__ import annotations

from typing import Callable

import numpy as np

from capmap.dualarm.job import JobInputs, PlanSettings, assembly_on
from capmap.dualarm.ocp.assembly import Assembly, warm_start
from capmap.dualarm.ocp.evaluate import fine_grid
from capmap.dualarm.ocp.motion import AssemblyMotion, plan_assembly
from capmap.dualarm.ocp.settings import SolveOptions
from capmap.dualarm.scene.robot import DualArm
from capmap.dualarm.scene.solids import Scene
from capmap.dualarm.scene.unknown import Grid, near_boxes
from capmap.dualarm.scene.unobserved import UnobservedCheck, swept_balls, unknown_mask, unobserved_check

__all__ = ["SOLVES", "plan_outside_unknown", "unobserved_reason"]

SOLVES = 3  # solves at most, each with the unknown boxes near the motion before it


def plan_outside_unknown(inputs: JobInputs, boxes: np.ndarray, ps: PlanSettings, log: Callable[[str], None]
                         ) -> tuple[DualArm, Scene, Assembly, AssemblyMotion, UnobservedCheck, int, int]:
    """Plan with the unknown boxes (B, 2, 3) m near the motion in the environment: first those within ``near_m``
    of the warm start; after each solve the motion (finer grid) is checked against every unknown voxel and the
    boxes near it are added, up to :data:`SOLVES` solves (``log``: the progress lines). Returns (robot, scene,
    assembly, motion, the check, boxes used, boxes in all)."""
    u = ps.unknown
    grid = Grid.over(u.work_lower, u.work_upper, u.voxel_m)
    mask = unknown_mask(grid, boxes)
    robot, corners = inputs.robot, inputs.scene.panel.corners()
    asm = assembly_on(inputs, ps.horizon)
    warm = warm_start(asm)  # the boxes do not change it
    balls, radii, _, slack = swept_balls(asm, robot, corners, warm[::5])
    use = near_boxes(boxes, balls.reshape(-1, 3), np.tile(radii + slack, len(balls)), u.near_m)
    for _ in range(SOLVES):
        log(f"unknown space: {int(use.sum())} of {len(boxes)} boxes near the motion go to the optimiser")
        asm = assembly_on(inputs, ps.horizon, boxes[use], u.voxel_m)
        m = plan_assembly(asm, robot, ps.weights, ps.solver, ps.fine_factor, SolveOptions(log=log), warm=warm)
        balls, radii, names, slack = swept_balls(asm, robot, corners, fine_grid(m.sol.xs, m.sol.us, asm.task.dt,
                                                                                 ps.fine_factor)[1])
        check = unobserved_check(balls, radii, names, grid, mask, slack=slack)
        if check.distance >= 0:
            break
        every = balls[::ps.fine_factor]
        more = near_boxes(boxes, every.reshape(-1, 3), np.tile(radii + slack, len(every)), u.near_m) & ~use
        if not more.any():
            break
        use |= more
    return robot, inputs.scene, asm, m, check, int(use.sum()), len(boxes)


def unobserved_reason(check: UnobservedCheck) -> str:
    """Why a planned motion is not a result to execute, when it reaches into space no camera observed after
    the :data:`SOLVES` solves ("" when it stays outside)."""
    if check.distance >= 0:
        return ""
    return (f"the optimised motion reaches {1e3 * -check.distance:.1f} mm into space no camera observed "
            f"({check.body} near {np.round(check.voxel_centre, 2).tolist()} m) after {SOLVES} solves with the unknown "
            "boxes near it; add a viewpoint of dualarm.cloud.viewpoints_m that sees that region")
