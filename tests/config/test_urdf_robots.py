"""URDF robot files: joints held fixed (``locked``), the arm's joints named (``joints``), and the URDF's
effort limits as the default joint torque limits. Independent checks: Pinocchio on the full URDF model
(fingers at their locked values) and the URDF's ``<limit effort>`` read with xml.etree."""

from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pinocchio as pin
import pytest
import yaml
from example_robot_data.robots_loader import getModelPath

from capmap.capacity.build import load_limits
from capmap.checks import check_run_config
from capmap.config import main_task
from capmap.config.capacity import TORQUE_FROM_CONFIG, TORQUE_FROM_URDF, LimitsConfig
from capmap.config.slices import stage_slice
from capmap.config.validation import load_yaml
from capmap.errors import ConfigError
from capmap.robots import load
from tests.scenario import ROOT, SSRMS_YAML

PANDA_YAML = ROOT / "config" / "robots" / "panda.yaml"
XARM_YAML = ROOT / "config" / "robots" / "xarm7.yaml"
PANDA_RUN = ROOT / "config" / "panda_joint4.yaml"
PANDA_URDF = Path(getModelPath("panda_description/urdf/panda.urdf")) / "panda_description/urdf/panda.urdf"
ARM = [f"panda_joint{i}" for i in range(1, 8)]
FINGERS = ("panda_finger_joint1", "panda_finger_joint2")


def _urdf_efforts(path: Path) -> dict[str, float]:
    """Each joint's <limit effort> in the URDF file, read with xml.etree (not Pinocchio)."""
    root = ElementTree.parse(path).getroot()
    return {j.get("name"): float(j.find("limit").get("effort")) for j in root.findall("joint")
            if j.find("limit") is not None}


def _panda_file(tmp_path, **changes) -> Path:
    """config/robots/panda.yaml with keys replaced (None: removed), written to tmp_path."""
    doc = yaml.safe_load(PANDA_YAML.read_text())
    for k, v in changes.items():
        if v is None:
            doc.pop(k, None)
        else:
            doc[k] = v
    p = tmp_path / "robot.yaml"
    p.write_text(yaml.safe_dump(doc))
    return p


def _error(path) -> str:
    with pytest.raises(ConfigError) as exc:
        load(path)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(str(path)), msg
    return msg


# --------------------------------------------------------------------------- locked joints


def test_the_panda_loads_as_a_serial_7_joint_arm():
    robot = load(PANDA_YAML)
    assert robot.n_joints == 7 and robot.joint_names == tuple(ARM)
    assert dict(robot.description.urdf_locked) == {"panda_finger_joint1": 0.04, "panda_finger_joint2": 0.04}
    assert robot.model.nq == robot.model.nv == 7


def test_the_reduced_model_equals_the_full_urdf_with_the_fingers_at_their_locked_values():
    robot = load(PANDA_YAML)
    full = pin.buildModelFromUrdf(str(PANDA_URDF))  # the whole URDF, 9 joints
    full.gravity = pin.Motion(np.array([0, 0, -9.81]), np.zeros(3))
    locked = dict(robot.description.urdf_locked)
    assert locked[FINGERS[0]] > 0  # a value other than the neutral one, so ignoring it would show
    fd, rd = full.createData(), robot.model.createData()
    shared = [f.name for f in full.frames if robot.model.existFrame(f.name) and f.name != "universe"]
    assert {"panda_hand_tcp", "panda_leftfinger", "panda_rightfinger", "panda_link7"} <= set(shared)
    rng = np.random.default_rng(7)
    lo, hi = full.lowerPositionLimit[:7], full.upperPositionLimit[:7]
    finger_q = [full.joints[full.getJointId(n)].idx_q for n in FINGERS]
    for _ in range(20):
        q = rng.uniform(lo, hi)
        qf = np.zeros(full.nq)
        qf[:7] = q
        qf[finger_q] = [locked[n] for n in FINGERS]
        pin.framesForwardKinematics(full, fd, qf)
        pin.framesForwardKinematics(robot.model, rd, q)
        for name in shared:
            a, b = fd.oMf[full.getFrameId(name)], rd.oMf[robot.model.getFrameId(name)]
            assert np.allclose(a.homogeneous, b.homogeneous, atol=1e-12), name
        # the end effector: the URDF's ee_frame
        assert np.allclose(robot.fk(q), fd.oMf[full.getFrameId("panda_hand_tcp")].homogeneous, atol=1e-12)
        # and the dynamics of the arm's joints (fingers at rest at their locked values)
        v, a = rng.normal(size=7), rng.normal(size=7)
        vf, af = np.zeros(full.nv), np.zeros(full.nv)
        vf[:7], af[:7] = v, a
        tau_full = pin.rnea(full, fd, qf, vf, af)[:7]
        assert np.allclose(pin.rnea(robot.model, rd, q, v, a), tau_full, atol=1e-9)


def test_an_unknown_locked_joint_names_its_key(tmp_path):
    msg = _error(_panda_file(tmp_path, locked={"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0,
                                               "panda_finger_joint3": 0.0}))
    assert "locked.panda_finger_joint3" in msg and "no movable joint" in msg


def test_a_locked_value_outside_the_joint_range_names_its_key(tmp_path):
    msg = _error(_panda_file(tmp_path, locked={"panda_finger_joint1": 0.05, "panda_finger_joint2": 0.0}))
    assert "locked.panda_finger_joint1 = 0.05 m is outside the joint's range [0, 0.04] m" in msg


def test_a_nan_locked_value_names_its_key(tmp_path):
    p = tmp_path / "robot.yaml"
    p.write_text(PANDA_YAML.read_text().replace("panda_finger_joint1: 0.04", "panda_finger_joint1: .nan"))
    msg = _error(p)
    assert "locked.panda_finger_joint1 = nan is not a finite number" in msg


def test_a_joint_neither_named_nor_locked_is_named(tmp_path):
    msg = _error(_panda_file(tmp_path, locked={"panda_finger_joint1": 0.0}))
    assert "panda_finger_joint2 are neither in joints nor in locked" in msg


def test_a_joint_both_named_and_locked_is_named(tmp_path):
    msg = _error(_panda_file(tmp_path, joints=ARM + ["panda_finger_joint1"]))
    assert "joints: panda_finger_joint1 is also in locked" in msg


def test_joints_out_of_chain_order_are_named(tmp_path):
    msg = _error(_panda_file(tmp_path, joints=[ARM[1], ARM[0], *ARM[2:]]))
    assert "is not the chain's order root first (panda_joint1, panda_joint2," in msg


def test_unlocked_fingers_are_named_as_not_revolute(tmp_path):
    msg = _error(_panda_file(tmp_path, locked=None, joints=None))
    assert "serial chain of 1-DOF revolute joints" in msg
    assert "panda_finger_joint1 (prismatic), panda_finger_joint2 (prismatic) are not" in msg


def test_a_tree_of_revolute_joints_is_not_a_serial_chain(tmp_path):
    # Baxter with its head and fingers locked: two 7-joint arms on one torso
    baxter = load_yaml(ROOT / "config" / "robots" / "baxter_dual.yaml")
    fingers = {f["joint"]: 0.0 for side in ("left", "right") for f in baxter["arms"][side]["fingers"]}
    p = tmp_path / "baxter.yaml"
    p.write_text(yaml.safe_dump({"name": "baxter", "locked": {**baxter["locked"], **fingers},
                                 "urdf": {**baxter["urdf"], "ee_frame": "left_gripper"}}))
    msg = _error(p)
    assert "are not a serial chain (right_s0 follows the base, not left_w2)" in msg


def test_locked_and_joints_are_for_urdf_robots_only(tmp_path):
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    doc["locked"] = {"joint1": 0.0}
    p = tmp_path / "dh.yaml"
    p.write_text(yaml.safe_dump(doc))
    assert "'locked' is only for URDF robots" in _error(p)


def test_a_second_7_dof_arm_loads_without_locking():
    robot = load(XARM_YAML)
    assert robot.n_joints == 7 and robot.joint_names == tuple(f"joint{i}" for i in range(1, 8))


# --------------------------------------------------------------------------- effort limits


@pytest.mark.parametrize("robot_file", [PANDA_YAML, XARM_YAML])
def test_effort_limits_are_the_urdf_s(robot_file):
    robot = load(robot_file)
    effort = _urdf_efforts(robot.description.urdf_path)
    assert robot.effort_limit_nm.tolist() == [effort[n] for n in robot.joint_names]
    lim = LimitsConfig.from_doc({"base_force_n": 1000, "base_moment_nm": 500}).for_robot(robot)
    assert lim.torque_limit_source == TORQUE_FROM_URDF
    assert np.array_equal(load_limits(lim, 7).joint_torque_nm, [effort[n] for n in robot.joint_names])


def _panda_run(**limits) -> dict:
    doc = load_yaml(PANDA_RUN)
    doc["limits"] = {"base_force_n": 1000, "base_moment_nm": 500, **limits}
    return doc


def test_the_run_takes_the_urdf_effort_limits_and_says_so():
    run = check_run_config(_panda_run(), "panda.yaml")
    effort = _urdf_efforts(PANDA_URDF)
    assert run.limits.joint_torque_nm == tuple(effort[n] for n in ARM)
    assert run.limits.torque_limit_source == TORQUE_FROM_URDF == "urdf effort"
    assert run.limits.describe() == "joint torque limits 87, 87, 87, 87, 12, 12, 12 N m (from urdf effort)"
    sl = stage_slice(run, "capacity")["run"]["limits"]  # what the capacity jobs read
    assert sl["joint_torque_nm"] == [effort[n] for n in ARM] and sl["torque_limit_source"] == "urdf effort"


def test_explicit_limits_override_the_urdf_s():
    run = check_run_config(_panda_run(joint_torque_nm=[50, 50, 50, 50, 10, 10, 10]), "panda.yaml")
    assert run.limits.joint_torque_nm == (50, 50, 50, 50, 10, 10, 10)
    assert run.limits.torque_limit_source == TORQUE_FROM_CONFIG == "config limits.joint_torque_nm"
    run = check_run_config(_panda_run(joint_torque_nm=30), "panda.yaml")
    assert run.limits.joint_torque_nm == 30 and run.limits.torque_limit_source == TORQUE_FROM_CONFIG


def test_a_zero_effort_without_explicit_limits_names_the_joint(tmp_path):
    urdf = tmp_path / "panda.urdf"
    text = PANDA_URDF.read_text()
    at = text.index('<joint name="panda_joint5"')
    urdf.write_text(text[:at] + text[at:].replace('effort="12.0"', 'effort="0"', 1))
    p = _panda_file(tmp_path, urdf={"path": str(urdf), "ee_frame": "panda_hand_tcp"})
    robot = load(p)
    with pytest.raises(ConfigError) as exc:
        LimitsConfig.from_doc({"base_force_n": 1, "base_moment_nm": 1}).for_robot(robot)
    msg = str(exc.value)
    assert "\n" not in msg and "a zero effort limit for joint panda_joint5" in msg and "limits.joint_torque_nm" in msg
    explicit = LimitsConfig.from_doc({"joint_torque_nm": 20, "base_force_n": 1, "base_moment_nm": 1})
    assert explicit.for_robot(robot).joint_torque_nm == 20  # an explicit limit needs no effort


def test_a_dh_robot_needs_explicit_joint_torque_limits(ssrms):
    with pytest.raises(ConfigError, match="limits.joint_torque_nm is required: the robot file .* gives DH rows"):
        LimitsConfig.from_doc({"base_force_n": 1, "base_moment_nm": 1}).for_robot(ssrms)


def test_the_branch_planner_s_tracking_step_is_in_the_plan_slice():
    run = check_run_config(load_yaml(PANDA_RUN), str(PANDA_RUN))
    job = main_task(run.task, run.failure, run.task.payload_kg[0])
    assert stage_slice(run, "plan", job)["run"]["planning"]["track_step_m"] == 0.005
    doc = load_yaml(PANDA_RUN)
    del doc["planning"]["track_step_m"]
    run = check_run_config(doc, str(PANDA_RUN))
    assert run.planning.track_step_m is None  # the planner's own (capmap.capacity.branch_moves.TRACK_STEP_M)
    assert stage_slice(run, "plan", job)["run"]["planning"]["track_step_m"] is None
