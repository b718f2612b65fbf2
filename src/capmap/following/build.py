"""The following family's one meeting of configuration and numerics: the ``follow`` section (and, for
the space case, the run's robot, lock, task and plan job) in, a :class:`FollowCase` out: the arm, the
path, the start configuration and the follower's settings (:class:`~capmap.following.follower.FollowSettings`),
with lengths checked against the robot and errors naming the config keys."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from capmap.config.run import RunConfig
from capmap.config.typed import per_item
from capmap.core.kinematics import rotation_from_rpy
from capmap.core.reduction import LockedArm, free
from capmap.following.follower import FollowSettings
from capmap.robots import load, run_arm

__all__ = ["FollowCase", "follow_case"]


@dataclass(frozen=True)
class FollowCase:
    """A follow case ready to run: the arm, its waypoints (W, 3) m followed as straight segments
    at ``rotation`` (3, 3) from q_start (n_active,) rad, the follower's settings and a label."""

    arm: LockedArm
    waypoints: np.ndarray
    rotation: np.ndarray
    q_start: np.ndarray
    settings: FollowSettings
    label: str


def follow_case(case: str, run: RunConfig, job=None, waypoints: pd.DataFrame | None = None) -> FollowCase:
    """The ``space`` case follows the verified path of its payload's plan job ``job`` (``waypoints``:
    that plan's table; the direct line where it found no path) on the run's locked arm; the ``ground``
    case a straight line from FK(q_start) on its own robot, every joint moving."""
    fol = run.follow
    if case == "space":
        sp, task = fol.space, run.task
        arm = run_arm(run)
        if waypoints.attrs["capmap"]["status"] == "ok":
            pts, label = waypoints[["x_m", "y_m", "z_m"]].to_numpy(), "planned path"
        else:
            pts, label = np.array([job.start_m, job.goal_m], dtype=float), "direct line (no planned path)"
        tau = per_item(sp.joint_torque_nm, arm.robot.n_joints, "follow.space.joint_torque_nm")[arm.active]
        settings = FollowSettings(payload_kg=float(sp.payload_kg), joint_torque_nm=tau, v_max_mps=task.v_max_mps,
                                  a_max_mps2=task.a_max_mps2, j_max_mps3=sp.j_max_mps3, period_s=fol.period_s,
                                  catch_up_hz=sp.catch_up_hz)
        q0 = np.deg2rad(np.asarray(job.q_start_deg, dtype=float))[arm.active]
        return FollowCase(arm, pts, rotation_from_rpy(task.orientation_rpy_deg), q0, settings, label)
    g = fol.ground
    arm = free(load(g.robot))
    q0 = np.deg2rad(np.asarray(g.q_start_deg, dtype=float))
    T0 = arm.fk(q0[None])[0]
    pts = np.array([T0[:3, 3], T0[:3, 3] + np.asarray(g.line_m, dtype=float)])
    tau = per_item(g.joint_torque_nm, arm.robot.n_joints, "follow.ground.joint_torque_nm")
    settings = FollowSettings(payload_kg=float(g.payload_kg), joint_torque_nm=tau, v_max_mps=g.v_max_mps,
                              a_max_mps2=g.a_max_mps2, j_max_mps3=g.j_max_mps3, period_s=fol.period_s,
                              catch_up_hz=g.catch_up_hz)
    return FollowCase(arm, pts, T0[:3, :3], q0, settings, "straight line")
