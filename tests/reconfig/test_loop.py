"""The closed chain split at any unlocked passive joint: the long side moves, and its end follows
T(fixed end) M(theta, d)^k exactly as the full robot model says a closed capture must."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.core import ik
from capmap.core.kinematics import pose_error, rotation_log
from capmap.errors import CapmapError
from capmap.reconfig.loop import capture_error, close_capture, split_loop
from capmap.reconfig.multiarm import platform_model
from tests.reconfig.conftest import CAPTURE_DEG, state_of


@pytest.mark.parametrize("capture, unlock, moving, fixed", [
    ("arm1_arm2", "arm1.P1", 10, 2),   # the spec's case: arm2 J1..J6, arm1 J6..J3 move
    ("arm1_arm2", "arm1.P2", 9, 3),    # arm1 J1, J2, J3 keep still
    ("arm1_arm2", "arm2.P1", 10, 2),   # in the other arm (the loop crosses it backwards)
    ("arm1_arm2", "arm2.P2", 9, 3),
])
def test_split_moves_the_side_with_more_joints(platform, captured, capture, unlock, moving, fixed):
    sp = split_loop(platform, capture, unlock, captured)
    assert (sp.moving.dof, sp.fixed.dof) == (moving, fixed)
    assert set(sp.moving.joints) | set(sp.fixed.joints) == {j for a in ("arm1", "arm2")
                                                             for j in platform.arm(a).revolute}
    short_arm = unlock.split(".")[0]
    assert all(j.startswith(short_arm) for j in sp.fixed.joints)  # the short side is the unlocked joint's root part


@pytest.mark.parametrize("unlock", ["arm1.P1", "arm1.P2", "arm2.P1", "arm2.P2"])
def test_law_target_closes_the_capture_in_the_full_model(platform, captured, unlock):
    """Move the unlocked joint to (theta, d), solve the long side onto the split's target, and check
    with the full Pinocchio model (passive joint at (theta, d)) that the capture holds."""
    model = platform_model(platform)
    sp = split_loop(platform, "arm1_arm2", unlock, captured)
    fixed_end = sp.fixed.chain.fk(sp.fixed.values(captured)[None])[0]
    for theta, d in [(0.0, 0.0), (np.deg2rad(25.0), 0.3), (np.deg2rad(-15.0), -0.2)]:
        target = sp.target(fixed_end, theta, d)
        q = ik.newton(sp.moving.chain, sp.moving.values(captured)[None], target, iters=30, damping=1e-6)
        # Newton converged to rounding of the forward kinematics (eps x metres): measured 1.3e-15 to 2.7e-15 over the
        # 5 OpenBLAS kernels (Prescott, Sandybridge, Haswell, Zen, SkylakeX), margin 370; the full model's capture
        # error below 1.8e-15 to 3.6e-15 (margin 2800)
        assert np.abs(pose_error(sp.moving.chain.fk(q), target)).max() < 1e-12
        state = captured.with_values(sp.moving.joints, q[0]).with_passive(unlock, theta, d)
        poses = dict(zip(("arm1.ee", "arm2.ee"), model.placements(state, ("arm1.ee", "arm2.ee"))))
        assert np.abs(capture_error(platform, "arm1_arm2", poses)).max() < 1e-11
    # the twist is the derivative of the target
    th, d, h = 0.3, 0.1, 1e-6
    Tp, Tm = sp.target(fixed_end, th + h, d + 0.5 * h)[0], sp.target(fixed_end, th - h, d - 0.5 * h)[0]
    v = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
    w = rotation_log(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
    assert np.allclose(sp.twist(fixed_end, np.array([1.0]), np.array([0.5]))[0], np.concatenate([v, w]), atol=1e-8)


def test_close_capture_is_ik_of_the_reconfigured_arm(platform):
    state = state_of(platform, CAPTURE_DEG)
    closed, dq = close_capture(platform, "arm1_arm2", "arm1", state)
    assert np.rad2deg(np.abs(dq)).max() < 1e-4  # the spec's arm 1 angles are the IK solution to 4 decimals
    assert all(closed.q[n] == state.q[n] for n in platform.arm("arm2").revolute)  # the other arm as given
    model = platform_model(platform)
    poses = dict(zip(("arm1.ee", "arm2.ee"), model.placements(closed, ("arm1.ee", "arm2.ee"))))
    # measured 3.3e-16 to 8.9e-16 over the 5 OpenBLAS kernels (Prescott, Sandybridge, Haswell, Zen, SkylakeX): margin 1100
    assert np.abs(capture_error(platform, "arm1_arm2", poses)).max() < 1e-12


def test_split_errors(platform, captured):
    with pytest.raises(CapmapError, match="not a passive one"):
        split_loop(platform, "arm1_arm2", "arm1.J3", captured)
    with pytest.raises(CapmapError, match="arm3.P1 is not on the closed chain through capture arm1_arm2"):
        split_loop(platform, "arm1_arm2", "arm3.P1", captured)
    with pytest.raises(CapmapError, match="no capture 'nope'"):
        split_loop(platform, "nope", "arm1.P1", captured)
