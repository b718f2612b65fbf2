"""The reconfiguration family's table (column schema, units in the names): one row per RK4 step
of a run, with every joint of the closed loop, the passive joint, the manipulability and the
closure and task errors."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.reconfig.planner import Reconfiguration
from capmap.reconfig.problem import ReconfigProblem

__all__ = ["column", "run_table"]


def column(joint: str) -> str:
    """Column stem of a qualified joint name: 'arm2.J1' -> 'arm2_j1'."""
    return joint.replace(".", "_").lower()


def run_table(method: str, problem: ReconfigProblem, run: Reconfiguration, closure: np.ndarray) -> pd.DataFrame:
    """One row per step of ``run``; ``closure`` (T, 6): the capture's closure error per step."""
    split = problem.split
    df = pd.DataFrame({"method": method, "t_s": run.t_s, "law_phase": run.u, "time_scale": run.time_scale})
    for c, j in enumerate(split.moving.joints):
        df[f"q_{column(j)}_deg"] = np.rad2deg(run.q[:, c])
    for j, v in zip(split.fixed.joints, split.fixed.values(problem.state)):
        df[f"q_{column(j)}_deg"] = np.rad2deg(v)
    for c, j in enumerate(split.moving.joints):
        df[f"qd_{column(j)}_deg_s"] = np.rad2deg(run.qd[:, c])
    for j in split.fixed.joints:
        df[f"qd_{column(j)}_deg_s"] = 0.0
    df["passive_theta_deg"] = np.rad2deg(run.theta)
    df["passive_d_m"] = run.d
    df["manipulability"] = run.m
    df["dm_dt"] = run.dm_dt
    df["min_singular_value"] = run.min_singular_value
    df["kappa"] = run.kappa
    df["closure_pos_err_m"] = np.linalg.norm(closure[:, :3], axis=1)
    df["closure_rot_err_rad"] = np.linalg.norm(closure[:, 3:], axis=1)
    df["task_pos_err_m"] = np.linalg.norm(run.task_error[:, :3], axis=1)
    df["task_rot_err_rad"] = np.linalg.norm(run.task_error[:, 3:], axis=1)
    return df
