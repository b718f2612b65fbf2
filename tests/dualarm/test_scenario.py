"""The spec's satellite-panel assembly on the default config (N = 500, dt = 0.02 s), with the
issue's required result checked by a second formulation: forward kinematics of the full,
unreduced URDF model (joints matched by name, the locked ones at their values), the task
written in poses rather than the optimiser's residuals, the motion re-integrated on a 5x
finer grid, limits from the URDF, and the closest pairs re-measured with coal."""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
import pytest

from capmap.config.dualarm import horizon, weights_config
from capmap.dualarm.build import weights
from capmap.dualarm.ocp.assembly import warm_start
from capmap.dualarm.ocp.settings import ALSettings
from capmap.dualarm.ocp.solver import initial_guess, solve
from tests.dualarm.conftest import SECTION
from tests.reference.coal_shapes import capsule, distance, triangle


@pytest.fixture(scope="module")
def solved(robot, scene, make_assembly):
    h = horizon(SECTION)
    assert (h.nodes, h.dt_s) == (500, 0.02)
    asm = make_assembly(h.nodes, h.dt_s, h.pre_insertion_node)
    xs0, us0 = initial_guess(warm_start(asm), asm.task.dt)
    t0 = time.perf_counter()
    sol = solve(asm, weights(weights_config(SECTION)), (robot.q_lower, robot.q_upper, robot.v_max),
                ALSettings(**SECTION["solver"]), xs0, us0)
    secs = time.perf_counter() - t0
    print(f"\nscenario: {len(sol.stats)} outer / {sum(s.inner_iterations for s in sol.stats)} FDDP iterations "
          f"in {secs:.1f} s")
    assert sol.converged, sol.message
    return asm, sol


@pytest.fixture(scope="module")
def full(robot):
    """The unreduced URDF model and a map from the 14 optimised joints to its configuration."""
    desc = robot.description
    model = pin.buildModelFromUrdf(str(desc.urdf))
    q_base = pin.neutral(model)
    for name, value in desc.locked.items():
        q_base[model.joints[model.getJointId(name)].idx_q] = value
    idx = np.array([model.joints[model.getJointId(n)].idx_q for n in robot.joint_names])

    def to_full(q14):
        q = np.repeat(q_base[None], len(q14), axis=0)
        q[:, idx] = q14
        return q
    return model, to_full, idx


def _gripper_poses(model, qs, robot):
    data = model.createData()
    fl = model.getFrameId(robot.description.grippers["left"])
    fr = model.getFrameId(robot.description.grippers["right"])
    out = []
    for q in qs:
        pin.framesForwardKinematics(model, data, q)
        out.append((data.oMf[fl].copy(), data.oMf[fr].copy()))
    return out


def test_closed_chain_and_path_errors(solved, full, robot, scene):
    asm, sol = solved
    model, to_full, _ = full
    poses = _gripper_poses(model, to_full(sol.xs[:, :14]), robot)
    L0, R0 = poses[0]
    rel0 = L0.inverse() * R0
    panel_in_left = L0.inverse() * pin.SE3(scene.start)  # the grasp as held at the start
    chain_p, chain_r, path_p, path_r = [], [], [], []
    pre, final = pin.SE3(scene.pre_insertion), pin.SE3(scene.final)
    n_pre, N = asm.task.n_transfer, asm.task.N
    axis = (final.translation - pre.translation) / np.linalg.norm(final.translation - pre.translation)
    for k, (L, R) in enumerate(poses):
        e = rel0.inverse() * (L.inverse() * R)
        chain_p.append(np.linalg.norm(e.translation))
        chain_r.append(np.linalg.norm(pin.log3(e.rotation)))
        P = L * panel_in_left
        if k < n_pre:  # the panel upright: its z axis vertical
            path_r.append(np.arccos(np.clip(P.rotation[2, 2], -1, 1)))
        elif k == n_pre or k == N:
            target = pre if k == n_pre else final
            path_p.append(np.linalg.norm(P.translation - target.translation))
            path_r.append(np.linalg.norm(pin.log3(target.rotation.T @ P.rotation)))
        else:  # on the insertion line (pre -> final), at the final orientation
            d = P.translation - pre.translation
            path_p.append(np.linalg.norm(d - (d @ axis) * axis))
            path_r.append(np.linalg.norm(pin.log3(final.rotation.T @ P.rotation)))
    print(f"closed chain {max(chain_p):.2e} m, {max(chain_r):.2e} rad; path {max(path_p):.2e} m, "
          f"{max(path_r):.2e} rad")
    assert max(chain_p) < 7e-7 and max(path_p) < 7e-7
    assert max(chain_r) < 1e-6 and max(path_r) < 1e-6
    assert np.abs(sol.xs[-1, 14:]).max() < 1e-6  # at rest at the end


def test_limits_from_the_urdf(solved, full):
    _, sol = solved
    model, _, idx = full
    q, v = sol.xs[:, :14], sol.xs[:, 14:]
    assert np.all(q >= model.lowerPositionLimit[idx] - 1e-9) and np.all(q <= model.upperPositionLimit[idx] + 1e-9)
    # between nodes q(t) is quadratic: its extremes are at the nodes or where v = 0
    assert np.all(np.abs(v) <= model.velocityLimit[idx] + 1e-9)  # v(t) is linear: nodes bound it


def test_safety_on_a_five_times_finer_grid_and_an_active_collision_constraint(solved):
    asm, sol = solved
    xs, us, dt = sol.xs, sol.us, asm.task.dt
    qs = [xs[k, :14] + xs[k, 14:] * tau + 0.5 * us[k] * tau**2 for k in range(len(us)) for tau in dt * np.arange(5) / 5]
    qs = np.array(qs + [xs[-1, :14]])
    model, data = asm.model, asm.model.createData()
    D = np.empty((len(qs), len(asm.pairs)))
    for i, q in enumerate(qs):
        pin.forwardKinematics(model, data, q)
        ev = asm.collision.evaluate(data, asm.pairs)
        D[i] = ev.distance
    names = np.array([f"{a} vs {b}" for a, b in zip(ev.first, ev.second)])
    print(f"min safety distance on the 5x grid {1e3 * D.min():.3f} mm ({names[D.min(axis=0).argmin()]})")
    assert D.min() >= 0.0
    near = np.flatnonzero(D.min(axis=0) <= 0.01)
    assert len(near), "no collision constraint within 1 cm"
    print("within 1 cm: " + ", ".join(sorted(set(names[near]))))
    # the 40 closest pairs re-measured with coal at their worst configuration (capsules, and one-triangle
    # meshes whose swept radius is subtracted)
    P = asm.collision.prims
    n_ss = len(asm.pairs.ss)

    def world(joint, pts):
        M = data.oMi[int(joint)] if joint > 0 else pin.SE3.Identity()
        return [M.act(x) for x in pts]

    for p in np.argsort(D.min(axis=0))[:40]:
        pin.forwardKinematics(model, data, qs[D[:, p].argmin()])
        i, j = asm.pairs.ss[p] if p < n_ss else asm.pairs.st[p - n_ss]
        first = capsule(*world(P.seg_joint[i], (P.seg_a[i], P.seg_b[i])), P.seg_r[i])
        if p < n_ss:
            second, r2 = capsule(*world(P.seg_joint[j], (P.seg_a[j], P.seg_b[j])), P.seg_r[j]), 0.0
        else:
            second, r2 = triangle(*world(P.tri_joint[j], P.tri_v[j])), P.tri_r[j]
        assert distance(*first, *second) - r2 == pytest.approx(D[:, p].min(), abs=1e-9), names[p]
