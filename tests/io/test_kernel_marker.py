"""The compiled kernels' marker: keyed by the robot file's content (not the checkout's path), and a shared
cache folder of other sources removed only once no run has used it for UNUSED_DAYS."""

import os
import time
from pathlib import Path

import numpy as np
import pytest

from capmap.core import ik
from capmap.core.reduction import lock
from capmap.io import kernel_marker
from capmap.robots import load

ROBOTS = Path(__file__).resolve().parents[2] / "config" / "robots"


def test_the_key_is_the_same_in_another_checkout(tmp_path):
    a, b = tmp_path / "one" / "ssrms7.yaml", tmp_path / "two" / "ssrms7.yaml"
    for f in (a, b):
        f.parent.mkdir()
        f.write_text("name: arm\n")
    assert kernel_marker.run_key(str(a), 2, 1.0, False, 7) == kernel_marker.run_key(str(b), 2, 1.0, False, 7)
    b.write_text("name: other arm\n")
    assert kernel_marker.run_key(str(a), 2, 1.0, False, 7) != kernel_marker.run_key(str(b), 2, 1.0, False, 7)


@pytest.mark.parametrize("robot_file", ["ssrms7.yaml", "panda.yaml", "xarm7.yaml", "ur5.yaml"])
def test_an_end_joints_angle_is_not_in_the_key_and_does_not_change_the_ik_method(robot_file):
    """The key leaves out the first and last joints' angles because the locked chain's IK method (what the
    kernels are compiled for) does not depend on them: checked on each arm at 7 angles; a middle joint's
    angle stays in the key."""
    path = str(ROBOTS / robot_file)
    robot = load(path)
    n = robot.n_joints
    for joint in (1, n):
        keys = {kernel_marker.run_key(path, joint, a, False, n) for a in (0.0, 1.0)}
        assert len(keys) == 1
        lo, hi = max(robot.q_lower[joint - 1], -np.pi), min(robot.q_upper[joint - 1], np.pi)
        assert len({ik.method_for(lock(robot, joint, a).chain) for a in np.linspace(lo, hi, 7)}) == 1
    assert kernel_marker.run_key(path, 3, 0.0, False, n) != kernel_marker.run_key(path, 3, 1.0, False, n)


def test_record_prunes_only_unused_shared_folders(tmp_path, monkeypatch):
    base = tmp_path / "cache"
    mine = base / "numba-0000000000000001"
    old, recent = base / "numba-0000000000000002", base / "numba-0000000000000003"
    for d in (mine, old, recent):
        d.mkdir(parents=True)
        (d / "kernels-x.ok").write_text("")
    month = time.time() - (kernel_marker.UNUSED_DAYS + 1) * 86400
    os.utime(old / "kernels-x.ok", (month, month))
    monkeypatch.setattr(kernel_marker.numba_config, "CACHE_DIR", str(mine))
    kernel_marker.record("a run")
    assert mine.is_dir() and recent.is_dir() and not old.exists()
    assert kernel_marker.is_warm("a run") and not kernel_marker.is_warm("another run")
