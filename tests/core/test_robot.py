import numpy as np
import pinocchio as pin
import yaml

from capmap.core.robot import build_robot
from capmap.robots import load, parse_robot
from tests.reference.newton_euler import craig_fk, craig_step, spec_table
from tests.scenario import Q_INI_DEG, SSRMS_YAML, X_INI, rpy_matrix


def test_fk_q_ini_matches_published_pose(ssrms):
    T = ssrms.fk(np.deg2rad(Q_INI_DEG))
    assert np.linalg.norm(T[:3, 3] - X_INI) < 1e-3


def test_fk_matches_independent_craig_recursion(ssrms):
    rng = np.random.default_rng(3)
    for q in rng.uniform(-np.pi, np.pi, (50, 7)):
        R, p = craig_fk(q)
        T = ssrms.fk(q)
        assert np.allclose(T[:3, 3], p, atol=1e-12)
        assert np.allclose(T[:3, :3], R, atol=1e-12)


def _standard_dh_doc():
    """The same arm rewritten in standard DH (shift alpha, a one row down; frame 0 extra, tool for frame 7)."""
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    rows = doc["dh"]["rows"]
    # modified row i: [alpha_{i-1}, a_{i-1}, off_i, d_i]; standard row i: [alpha_i, a_i, off_i, d_i]
    # Frame assignment differs, so compare only end-effector poses with the frame-0 and tool
    # transforms that make them agree: T_mod = Rx(a0)Tx(a0') * prod[Rz Tz Tx(a_i) Rx(alpha_i)] * ...
    std_rows = [[rows[i + 1][0], rows[i + 1][1], rows[i][2], rows[i][3]] for i in range(6)] + [[0, 0, rows[6][2], rows[6][3]]]
    doc["dh"] = {"convention": "standard", "rows": std_rows}
    return doc


def test_standard_dh_gives_same_end_effector_pose():
    # alpha_0 = a_0 = 0 for this arm, so the standard rewrite needs no base transform;
    # link frames differ, so only kinematics is compared (links keep their data but move frames).
    doc = _standard_dh_doc()
    robot_std = build_robot(parse_robot(doc, "std"))
    robot_mod = load(SSRMS_YAML)
    rng = np.random.default_rng(4)
    q = rng.uniform(-np.pi, np.pi, (30, 7))
    assert np.allclose(robot_std.fk(q), robot_mod.fk(q), atol=1e-12)


def _urdf_of_spec(tmp_path):
    """A URDF of the spec's arm written from the DH table (joint origins = Craig steps with q = 0)."""
    alpha, a, off, d, links = spec_table()
    parts = ['<robot name="ssrms_urdf">', '<link name="base"/>']
    for i in range(7):
        m, c, Ic = links[i]
        parts.append(
            f'<link name="l{i + 1}"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}" rpy="0 0 0"/><mass value="{m}"/>'
            f'<inertia ixx="{Ic[0, 0]}" iyy="{Ic[1, 1]}" izz="{Ic[2, 2]}" ixy="0" ixz="0" iyz="0"/></inertial></link>')
        R, p = craig_step(alpha[i], a[i], off[i], d[i])
        rpy = pin.rpy.matrixToRpy(R)
        parent = "base" if i == 0 else f"l{i}"
        parts.append(
            f'<joint name="j{i + 1}" type="revolute"><parent link="{parent}"/><child link="l{i + 1}"/>'
            f'<origin xyz="{p[0]} {p[1]} {p[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/><axis xyz="0 0 1"/>'
            f'<limit lower="-3.14159265358979" upper="3.14159265358979" effort="700" velocity="1"/></joint>')
    parts.append('<link name="tool"/><joint name="jt" type="fixed"><parent link="l7"/><child link="tool"/>'
                 '<origin xyz="0 0 0" rpy="0 0 0"/></joint></robot>')
    path = tmp_path / "ssrms.urdf"
    path.write_text("\n".join(parts))
    return path


def test_urdf_robot_matches_dh_robot(tmp_path):
    _urdf_of_spec(tmp_path)  # writes tmp_path/ssrms.urdf
    (tmp_path / "r.yaml").write_text(yaml.safe_dump({"name": "ssrms_urdf", "urdf": {"path": "ssrms.urdf", "ee_frame": "tool"}}))
    ru = load(tmp_path / "r.yaml")
    rd = load(SSRMS_YAML)
    assert ru.n_joints == 7
    rng = np.random.default_rng(5)
    for q, v, a in rng.uniform(-1, 1, (10, 3, 7)):
        assert np.allclose(ru.fk(q), rd.fk(q), atol=1e-9)
        tu = pin.rnea(ru.model, ru.model.createData(), q, v, a)
        td = pin.rnea(rd.model, rd.model.createData(), q, v, a)
        assert np.allclose(tu, td, rtol=1e-9, atol=1e-7)
    assert np.allclose(ru.q_lower, -np.pi, atol=1e-6)


def test_tool_transform_applies(tmp_path):
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    doc["tool"] = {"xyz_m": [0.1, 0.2, 0.3], "rpy_deg": [10, 20, 30]}
    robot = build_robot(parse_robot(doc, "tool"))
    q = np.deg2rad(Q_INI_DEG)
    R, p = craig_fk(q)
    T = robot.fk(q)
    assert np.allclose(T[:3, 3], p + R @ [0.1, 0.2, 0.3], atol=1e-12)
    assert np.allclose(T[:3, :3], R @ rpy_matrix(*np.deg2rad([10, 20, 30])), atol=1e-12)
