import numpy as np
import pinocchio as pin
import pytest

from capmap.core.reduction import lock
from capmap.errors import CapmapError


@pytest.mark.parametrize("joint", range(1, 8))
def test_locked_fk_equals_full_fk_with_joint_at_theta(ssrms, joint):
    rng = np.random.default_rng(joint)
    theta = rng.uniform(-np.pi, np.pi)
    arm = lock(ssrms, joint, theta)
    assert arm.n_active == 6 and (joint - 1) not in arm.active
    q_act = rng.uniform(-np.pi, np.pi, (20, 6))
    q_full = np.insert(q_act, joint - 1, theta, axis=1)  # independent of LockedArm.full_q
    assert np.allclose(arm.fk(q_act), ssrms.fk(q_full), atol=1e-12)
    # the Pinocchio reduced model agrees too
    data = arm.reduced_model.createData()
    for qa, qf in zip(q_act[:3], q_full[:3]):
        pin.framesForwardKinematics(arm.reduced_model, data, qa)
        assert np.allclose(data.oMf[arm.reduced_ee_frame_id].homogeneous, ssrms.fk(qf), atol=1e-12)


@pytest.mark.parametrize("joint", [0, 8, -1, 2.5, True])
def test_joint_index_out_of_range_is_one_line(ssrms, joint):
    with pytest.raises(CapmapError, match=r"the locked joint = .* out of range: ssrms7 has joints 1..7") as err:
        lock(ssrms, joint, 0.0)
    assert err.value.in_terms(joint="lock.joint").startswith("lock.joint = ")


def test_lock_angle_outside_range(ssrms):
    with pytest.raises(CapmapError, match=r"the lock angle = 300 is outside joint 3's range \[-270, 270\]"):
        lock(ssrms, 3, np.deg2rad(300))
