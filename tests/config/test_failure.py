"""The failure in one edit (capmap.config.failure): lock angle, start and start configuration
resolved from q_ini, checked against an independent DH forward kinematics and a brute-force
random-restart IK (tests/reference/ik_oracle.py)."""

import numpy as np
import pytest
import yaml

from capmap.capacity.build import resolve_failure
from capmap.config import parse_config
from capmap.errors import ConfigError
from tests.reference.ik_oracle import DHArm, solve_all
from tests.scenario import ROOT, SSRMS_YAML, TASK_R, X_INI

Q_INI = [100, 124, 98, 130, 146, 174, 57]


def _resolve(ssrms, lock, **task):
    doc = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    doc["lock"] = lock
    doc["task"].update(task)
    for k in [k for k, v in task.items() if v is None]:
        doc["task"].pop(k)
    cfg = parse_config(doc)
    return resolve_failure(ssrms, cfg.lock, cfg.task)[0]


def _oracle_nearest(joint, angle_deg, start, q_ini_deg):
    """Every IK solution at the start by dense restarts (independent), then the nearest to q_ini."""
    arm = DHArm(yaml.safe_load(SSRMS_YAML.read_text()), joint, angle_deg)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = TASK_R, start
    sols = solve_all(arm, T[None], 400, np.random.default_rng(0))[0]
    ref = np.deg2rad(np.delete(q_ini_deg, joint - 1))
    d = np.abs(np.mod(sols - ref + np.pi, 2 * np.pi) - np.pi).max(axis=1)
    return arm, sols, np.rad2deg(d.min())


@pytest.mark.parametrize("lock, angle", [({"joint": 1}, 100), ({"joint": 3}, 98), ({"joint": 7}, 57),
                                         ({"joint": 1, "angle_deg": 90}, 90), ({"joint": 5, "angle_deg": 40}, 40)])
def test_start_is_the_nearest_exact_branch(ssrms, lock, angle):
    f = _resolve(ssrms, lock)
    assert f.joint == lock["joint"] and f.angle_deg == angle and f.q_start_deg[lock["joint"] - 1] == angle
    assert f.angle_given == ("angle_deg" in lock)
    arm, sols, nearest_deg = _oracle_nearest(lock["joint"], angle, X_INI, Q_INI)
    T = arm.fk(np.deg2rad(np.delete(f.q_start_deg, lock["joint"] - 1))[None])[0]
    assert np.abs(T[:3, 3] - X_INI).max() < 1e-9 and np.abs(T[:3, :3] - TASK_R).max() < 1e-9  # exact, independent FK
    assert f.n_branches == len(sols)
    assert f.offset_deg == pytest.approx(nearest_deg, abs=1e-6)  # no other branch is nearer q_ini


def test_start_defaults_to_the_end_effector_at_q_ini(ssrms):
    # a q_ini whose end effector has the task orientation exactly: the start branch nearest (scenario)
    f0 = _resolve(ssrms, {"joint": 1})
    f = _resolve(ssrms, {"joint": 1}, q_ini_deg=list(f0.q_start_deg), start_m=None)
    arm = DHArm(yaml.safe_load(SSRMS_YAML.read_text()))
    assert np.allclose(f.start_m, arm.fk(np.deg2rad(f0.q_start_deg)[None])[0, :3, 3], atol=1e-9)
    assert not f.start_given and f.offset_deg < 1e-6 and np.allclose(f.q_start_deg, f0.q_start_deg, atol=1e-6)


def test_a_rough_q_ini_still_names_a_branch_and_says_how_rough(ssrms):
    f = _resolve(ssrms, {"joint": 1}, q_ini_deg=[100, 124, 98, 140, 146, 174, 57])
    assert 9 < f.offset_deg < 11 and "deg from task.orientation_rpy_deg" in f.describe()
    assert f.ini_miss_m > 0.1


@pytest.mark.parametrize("lock, task, message", [
    ({"joint": 4, "angle_deg": 40}, {}, "task.start_m [0.379, 4.843, 1.888] m is not reachable"),
    ({"joint": 1, "angle_deg": 400}, {}, "lock.angle_deg = 400 is outside joint 1's range"),
    ({"joint": 2}, {"q_ini_deg": [100, 280, 98, 130, 146, 174, 57]}, "task.q_ini_deg[1] = 280 is outside"),
    ({"joint": 9}, {}, "lock.joint = 9 is out of range"),
    ({"joint": 1}, {"q_ini_deg": [100, 124]}, "task.q_ini_deg has 2 values but ssrms7 has 7 joints"),
])
def test_bad_failures_name_the_key(ssrms, lock, task, message):
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace(".", r"\.")):
        _resolve(ssrms, lock, **task)
