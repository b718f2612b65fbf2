import numpy as np
import pinocchio as pin

from capmap.core.kinematics import pose_error, rotation_log


def test_chain_jacobian_matches_finite_differences(scenario_arm):
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, (5, 6))
    T, J = scenario_arm.chain.jacobian(q)
    h = 1e-6
    for k in range(6):
        dq = np.zeros(6)
        dq[k] = h
        Tp, Tm = scenario_arm.fk(q + dq), scenario_arm.fk(q - dq)
        dv = (Tp[:, :3, 3] - Tm[:, :3, 3]) / (2 * h)
        dw = np.array([pin.log3(a[:3, :3] @ b[:3, :3].T) for a, b in zip(Tp, Tm)]) / (2 * h)
        assert np.allclose(J[:, :3, k], dv, atol=1e-7)
        assert np.allclose(J[:, 3:, k], dw, atol=1e-7)


def test_chain_jacobian_matches_pinocchio(scenario_arm):
    arm = scenario_arm
    data = arm.reduced_model.createData()
    q = np.random.default_rng(1).uniform(-np.pi, np.pi, 6)
    _, J = arm.chain.jacobian(q)
    Jp = pin.computeFrameJacobian(arm.reduced_model, data, q, arm.reduced_ee_frame_id, pin.LOCAL_WORLD_ALIGNED)
    assert np.allclose(J[0], Jp, atol=1e-12)


def test_reversed_chain_is_the_inverse(scenario_arm):
    chain = scenario_arm.chain
    q = np.random.default_rng(2).uniform(-np.pi, np.pi, (10, 6))
    T = chain.fk(q)
    Tr = chain.reversed().fk(-q[:, ::-1])
    assert np.allclose(T @ Tr, np.eye(4), atol=1e-12)


def test_rotation_log_matches_pinocchio_including_near_pi():
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(200, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.concatenate([rng.uniform(0, np.pi, 150), np.pi - 10.0 ** rng.uniform(-12, -3, 50)])
    R = np.array([pin.exp3(a * t) for a, t in zip(axes, angles)])
    w = rotation_log(R)
    assert np.allclose(w, axes * angles[:, None], atol=1e-7)


def test_pose_error_zero_at_target():
    T = np.eye(4)[None]
    assert np.allclose(pose_error(T, T), 0)


def test_jacobian_derivatives_match_finite_differences(scenario_arm):
    chain = scenario_arm.chain
    q = np.random.default_rng(9).uniform(-np.pi, np.pi, (4, 6))
    T, J, dJ = chain.jacobian_derivatives(q)
    assert np.allclose(T, chain.fk(q)) and np.allclose(J, chain.jacobian(q)[1])
    h = 1e-6
    for i in range(6):
        e = np.zeros(6)
        e[i] = h
        fd = (chain.jacobian(q + e)[1] - chain.jacobian(q - e)[1]) / (2 * h)
        assert np.allclose(dJ[:, i], fd, atol=1e-8)


def test_inverted_chain_takes_the_same_angles_reversed(scenario_arm):
    chain = scenario_arm.chain
    q = np.random.default_rng(10).uniform(-np.pi, np.pi, (6, 6))
    assert np.allclose(chain.fk(q) @ chain.inverted().fk(q[:, ::-1]), np.eye(4), atol=1e-12)
    both = chain.then(chain.inverted())  # there and back again
    assert both.n == 12 and np.allclose(both.fk(np.concatenate([q, q[:, ::-1]], axis=1)), np.eye(4), atol=1e-12)
