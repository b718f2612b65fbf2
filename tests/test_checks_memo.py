"""The dual-arm build the pre-run check remembers (capmap.checks.dual_arm_limits): the limits it
reads back are the build's; a changed mesh, URDF or robot file, another part thickness or code builds
again, so a broken mesh is still found before any job; an unreadable memo is built again."""

import pytest

from capmap import checks
from capmap.dualarm.build import load_dual_arm_file
from capmap.dualarm.scene.robot import build_dual_arm
from capmap.errors import CapmapError
from tests.config.test_referenced_files import MESHES, local  # noqa: F401 (the fixture)

VISUAL = next(m for m in MESHES if "collision" not in m)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CAPMAP_NUMBA_BASE", str(tmp_path / "cache"))
    return tmp_path / "cache" / "checks"


def _no_build(monkeypatch):
    def refuse(*a, **k):
        raise AssertionError("built although remembered")
    monkeypatch.setattr("capmap.dualarm.scene.robot.build_dual_arm", refuse)  # where the check imports it from


def test_the_remembered_limits_are_the_builds(local, cache, monkeypatch):  # noqa: F811
    robot = local / "robot.yaml"
    built = build_dual_arm(load_dual_arm_file(robot), 0.016)
    first = checks.dual_arm_limits(str(robot), 0.016)
    assert len(list(cache.glob("dual-arm-*.json"))) == 1
    _no_build(monkeypatch)
    again = checks.dual_arm_limits(str(robot), 0.016)
    for got in (first, again):
        assert got[0] == built.description.name
        assert (got[1] == built.q_lower).all() and (got[2] == built.q_upper).all()  # JSON keeps doubles exactly


@pytest.mark.parametrize("change", ["mesh", "urdf", "robot", "thickness"])
def test_a_change_builds_again(local, cache, change):  # noqa: F811
    robot = local / "robot.yaml"
    before = checks._memo_file(str(robot), 0.016)
    thickness = 0.016
    if change == "mesh":
        with open(local / VISUAL, "a") as f:
            f.write("<!-- changed -->\n")
    elif change == "urdf":
        with open(local / "baxter.urdf", "a") as f:
            f.write("<!-- changed -->\n")
    elif change == "robot":
        with open(robot, "a") as f:
            f.write("# changed\n")
    else:
        thickness = 0.018
    assert checks._memo_file(str(robot), thickness) != before


def test_a_broken_mesh_is_found_after_a_remembered_build(local, cache):  # noqa: F811
    robot = local / "robot.yaml"
    checks.dual_arm_limits(str(robot), 0.016)
    (local / VISUAL).write_bytes(b"\x00\x01 not a mesh \xff" * 64)
    with pytest.raises(CapmapError, match="cannot be loaded"):
        checks.dual_arm_limits(str(robot), 0.016)


def test_an_unreadable_memo_is_built_again(local, cache):  # noqa: F811
    robot = local / "robot.yaml"
    checks.dual_arm_limits(str(robot), 0.016)
    memo = checks._memo_file(str(robot), 0.016)
    memo.write_text("{not json")
    name, lo, hi = checks.dual_arm_limits(str(robot), 0.016)
    assert name and len(lo) == len(hi) == 14
    assert memo.read_text().startswith("{\"name\"")  # written again


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_special_robot_file_is_one_line_before_any_hashing(tmp_path, cache, kind):
    """The robot file's own checks come before its content is hashed for the memo: a FIFO (which would
    block a read) or a device (endless) is the loader's one-line error, not a hang."""
    import os
    import signal

    from capmap.errors import ConfigError

    if kind == "fifo":
        path = tmp_path / "robot.yaml"
        os.mkfifo(path)
    else:
        path = "/dev/zero"
    signal.signal(signal.SIGALRM, lambda *a: (_ for _ in ()).throw(TimeoutError("hung on the robot file")))
    signal.alarm(20)
    try:
        with pytest.raises(ConfigError, match="not a regular file|special file|device|FIFO"):
            checks.dual_arm_limits(str(path), 0.016)
    finally:
        signal.alarm(0)
