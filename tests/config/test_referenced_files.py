"""What a robot file's content hash covers: the file, its URDF and, for a dual-arm robot, the URDF's
collision and visual meshes (its capsules cover both) found as Pinocchio finds them; a point cloud is
hashed, never parsed."""

import shutil

import pytest
import yaml

from capmap.config import robot_file
from capmap.config.robot_file import referenced_files
from capmap.dualarm.build import load_dual_arm_file
from capmap.dualarm.scene.robot import build_dual_arm
from capmap.errors import ConfigError
from capmap.io.fingerprint import file_fingerprints
from tests.scenario import ROOT

BAXTER = ROOT / "config" / "robots" / "baxter_dual.yaml"
PREFIX = "package://example-robot-data/robots/baxter_description/"
MESHES = tuple(m.replace(PREFIX, "") for m in robot_file._meshes(load_dual_arm_file(BAXTER).urdf))  # every DAE named
PEDESTAL = "meshes/base/pedestal_link_collision.DAE"
assert PEDESTAL in MESHES


def _mesh_paths(robot) -> set[str]:
    return {o.meshPath for gm in (robot.geometry, robot.visual) for o in gm.geometryObjects if o.meshPath.endswith(".DAE")}


@pytest.fixture
def local(tmp_path):
    """Baxter's dual-arm file with its URDF and every mesh it names (collision and visual) copied beside
    it, named relatively."""
    desc = load_dual_arm_file(BAXTER)
    src = desc.urdf.parents[1]  # .../baxter_description
    for rel in MESHES:
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(src / rel, tmp_path / rel)
    (tmp_path / "baxter.urdf").write_text(desc.urdf.read_text().replace(PREFIX, ""))
    doc = yaml.safe_load(BAXTER.read_text())
    doc["urdf"] = {"path": "baxter.urdf"}
    (tmp_path / "robot.yaml").write_text(yaml.safe_dump(doc))
    return tmp_path


def test_the_packaged_robot_covers_the_meshes_pinocchio_reads():
    files = referenced_files(BAXTER)
    assert files[0] == BAXTER and files[1].name == "baxter.urdf"
    assert {str(p) for p in files[2:]} == _mesh_paths(build_dual_arm(load_dual_arm_file(BAXTER)))


def test_a_changed_mesh_changes_the_fingerprints(local):
    robot = local / "robot.yaml"
    files = referenced_files(robot)
    assert {str(p) for p in files[2:]} == _mesh_paths(build_dual_arm(load_dual_arm_file(robot)))
    before = file_fingerprints(files)
    assert files == [robot, local / "baxter.urdf", *(local / m for m in MESHES)] and len(before) == 2 + len(MESHES)
    with open(local / MESHES[0], "a") as f:
        f.write("<!-- another mesh -->\n")
    after = file_fingerprints(referenced_files(robot))
    assert [k for k in before if before[k] != after[k]] == [".../" + MESHES[0]]  # absolute: named by 3 parts


def _error(robot) -> str:
    with pytest.raises(ConfigError) as exc:
        load_dual_arm_file(robot)
    msg = str(exc.value)
    assert "\n" not in msg and str(robot) in msg and "baxter.urdf" in msg
    return msg


def test_a_missing_mesh_is_one_line_naming_it(local):
    (local / PEDESTAL).unlink()
    assert "mesh 'meshes/base/pedestal_link_collision.DAE': not found" in _error(local / "robot.yaml")
    assert local / PEDESTAL not in referenced_files(local / "robot.yaml")  # left to the loader's error


def test_a_mesh_that_is_no_file_or_of_an_unknown_scheme_is_one_line(local):
    urdf = local / "baxter.urdf"
    text = urdf.read_text()
    (local / PEDESTAL).unlink()
    (local / PEDESTAL).mkdir()
    assert "not a regular file" in _error(local / "robot.yaml")
    urdf.write_text(text.replace(PEDESTAL, f"file://{local}/absent.DAE"))
    assert f"{local}/absent.DAE is missing" in _error(local / "robot.yaml")
    urdf.write_text(text.replace(PEDESTAL, "http://example.org/m.DAE"))
    assert "scheme http:// is not handled" in _error(local / "robot.yaml")


def test_package_names_resolve_like_pinocchio(local, monkeypatch, tmp_path_factory):
    ros = tmp_path_factory.mktemp("ros")
    (ros / "mine/meshes").mkdir(parents=True)
    shutil.copy(local / PEDESTAL, ros / "mine/meshes/pedestal.DAE")
    urdf = local / "baxter.urdf"
    urdf.write_text(urdf.read_text().replace(PEDESTAL, "package://mine/meshes/pedestal.DAE"))
    assert "not found" in _error(local / "robot.yaml")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ros))  # Pinocchio searches it after the package directory
    robot = build_dual_arm(load_dual_arm_file(local / "robot.yaml"))
    assert str(ros / "mine/meshes/pedestal.DAE") in _mesh_paths(robot)
    assert ros / "mine/meshes/pedestal.DAE" in referenced_files(local / "robot.yaml")


def test_a_point_cloud_is_hashed_not_parsed(tmp_path, monkeypatch):
    cloud = tmp_path / "cloud.csv"
    cloud.write_text("x,y,z\n0,0,0\n")

    def refuse(path):
        raise AssertionError(f"parsed {path}")

    monkeypatch.setattr(robot_file, "load_yaml", refuse)
    assert referenced_files(cloud) == [cloud]
    with pytest.raises(AssertionError):
        referenced_files(tmp_path / "robot.YML")


def test_a_mesh_that_is_not_a_mesh_is_one_line_before_any_job(local):
    """A collision mesh named /etc/shadow (or any file of no mesh kind) is refused by the check, not
    handed to assimp inside a job (whose outputs Snakemake would have deleted)."""
    urdf = local / "baxter.urdf"
    (local / "secret").write_text("root:x:0:0\n")
    urdf.write_text(urdf.read_text().replace(PEDESTAL, f"file://{local}/secret"))
    assert "is not a mesh file (.3ds, .dae" in _error(local / "robot.yaml")
