"""The drives of a robot file (rotor inertia, friction): a DH robot's list, a URDF robot's mapping, the
URDF's <dynamics> read by default and overridden by explicit values, and every bad value one line
naming its key. Independent check: the URDF's <dynamics> attributes read with xml.etree."""

from __future__ import annotations

from xml.etree import ElementTree

import numpy as np
import pytest
import yaml

from capmap.robots import load
from tests.config.test_urdf_robots import _error  # one line naming the file: the robot files' check
from tests.scenario import ROOT, SSRMS_YAML

UR5_DRIVES = ROOT / "config" / "robots" / "ur5_drives.yaml"
UR5_JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
              "wrist_3_joint"]


def _write(tmp_path, doc, name="robot.yaml"):
    p = tmp_path / name
    p.write_text(yaml.safe_dump(doc))
    return p


def _ur5_with_dynamics(tmp_path, damping, friction):
    """A copy of the UR5 URDF whose joints carry <dynamics damping friction> (lists over UR5_JOINTS), and a
    robot file for it without drives."""
    doc = yaml.safe_load(UR5_DRIVES.read_text())
    robot = load(UR5_DRIVES)
    tree = ElementTree.parse(robot.description.urdf_path)
    for j in tree.getroot().findall("joint"):
        if j.get("name") in UR5_JOINTS:
            k = UR5_JOINTS.index(j.get("name"))
            dyn = j.find("dynamics") if j.find("dynamics") is not None else ElementTree.SubElement(j, "dynamics")
            dyn.set("damping", str(damping[k]))
            dyn.set("friction", str(friction[k]))
    tree.write(tmp_path / "ur5.urdf")
    doc["urdf"] = {"path": "ur5.urdf", "ee_frame": "tool0"}
    doc.pop("drives")
    return doc


def test_the_ur5_drives_file_states_rotor_inertia_times_ratio_squared_and_its_friction():
    doc = yaml.safe_load(UR5_DRIVES.read_text())["drives"]
    robot = load(UR5_DRIVES)
    for k, name in enumerate(UR5_JOINTS):
        d = doc[name]
        assert robot.armature_kgm2[k] == pytest.approx(d["rotor_inertia_kgm2"] * d["gear_ratio"] ** 2, rel=1e-15)
        assert robot.coulomb_nm[k] == d["friction"]["coulomb_nm"] and robot.viscous_nms[k] == d["friction"]["viscous_nms"]


def test_urdf_dynamics_are_read_by_default_and_explicit_values_override_them(tmp_path):
    damping, friction = [0.5, 0.6, 0.7, 0.1, 0.2, 0.3], [2.0, 2.5, 3.0, 0.4, 0.5, 0.6]
    doc = _ur5_with_dynamics(tmp_path, damping, friction)
    robot = load(_write(tmp_path, doc))
    root = ElementTree.parse(tmp_path / "ur5.urdf").getroot()  # what the URDF says, read here
    dyn = {j.get("name"): j.find("dynamics") for j in root.findall("joint") if j.get("name") in UR5_JOINTS}
    assert np.array_equal(robot.viscous_nms, [float(dyn[n].get("damping")) for n in UR5_JOINTS])
    assert np.array_equal(robot.coulomb_nm, [float(dyn[n].get("friction")) for n in UR5_JOINTS])
    assert np.all(robot.armature_kgm2 == 0)
    doc["drives"] = {"elbow_joint": {"armature_kgm2": 0.25, "friction": {"coulomb_nm": 9.0}}}
    robot = load(_write(tmp_path, doc))
    assert robot.coulomb_nm[2] == 9.0 and robot.viscous_nms[2] == 0.7  # viscous not stated: the URDF's
    assert robot.armature_kgm2[2] == 0.25 and np.all(np.delete(robot.armature_kgm2, 2) == 0)
    assert np.array_equal(np.delete(robot.coulomb_nm, 2), np.delete(friction, 2))


def test_a_dh_robot_takes_one_drive_per_joint(tmp_path):
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    n = len(doc["dh"]["rows"])
    doc["drives"] = [{"armature_kgm2": float(k), "friction": {"coulomb_nm": 2.0 * k, "viscous_nms": 0.5}} for k in range(n)]
    robot = load(_write(tmp_path, doc))
    assert np.array_equal(robot.armature_kgm2, np.arange(n)) and np.array_equal(robot.coulomb_nm, 2.0 * np.arange(n))
    assert np.all(robot.viscous_nms == 0.5)


@pytest.mark.parametrize("drives, key", [
    ({"elbow": {"armature_kgm2": 1.0}}, "drives.elbow: not a joint of the arm"),
    ({"elbow_joint": {"armature_kgm2": -1.0}}, "drives.elbow_joint.armature_kgm2"),
    ({"elbow_joint": {"armature_kgm2": float("nan")}}, "drives.elbow_joint.armature_kgm2"),
    ({"elbow_joint": {"friction": {"coulomb_nm": float("inf")}}}, "drives.elbow_joint.friction.coulomb_nm"),
    ({"elbow_joint": {"friction": {"viscous_nms": -0.1}}}, "drives.elbow_joint.friction.viscous_nms"),
    ({"elbow_joint": {"friction": {"dry_nm": 1.0}}}, "dry_nm"),
    ({"elbow_joint": {"rotor_inertia_kgm2": 1e-4}}, "drives.elbow_joint: rotor_inertia_kgm2 and gear_ratio go together"),
    ({"elbow_joint": {"gear_ratio": 0}}, "drives.elbow_joint.gear_ratio"),
    ({"elbow_joint": {"armature_kgm2": 0.1, "rotor_inertia_kgm2": 1e-4, "gear_ratio": 100}},
     "drives.elbow_joint: give armature_kgm2 or rotor_inertia_kgm2"),
    ([{"armature_kgm2": 0.1}], "drives: a URDF robot's drives are a mapping"),
])
def test_a_bad_drive_is_one_line_naming_its_key(tmp_path, drives, key):
    doc = yaml.safe_load(UR5_DRIVES.read_text())
    doc["drives"] = drives
    assert key in _error(_write(tmp_path, doc))


def test_a_dh_robot_s_drives_are_a_list_of_its_joints(tmp_path):
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    doc["drives"] = [{"armature_kgm2": 1.0}] * 3
    assert "drives has 3 entries but dh.rows has 7" in _error(_write(tmp_path, doc))
    doc["drives"] = {"joint1": {"armature_kgm2": 1.0}}
    assert "a DH robot's drives are a list" in _error(_write(tmp_path, doc))


def test_a_locked_joint_has_no_drive(tmp_path):
    doc = yaml.safe_load((ROOT / "config" / "robots" / "panda.yaml").read_text())
    doc["drives"] = {"panda_finger_joint1": {"armature_kgm2": 0.1}}
    assert "drives.panda_finger_joint1: not a joint of the arm (it is locked)" in _error(_write(tmp_path, doc))
