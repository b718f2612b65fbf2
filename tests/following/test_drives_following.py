"""Following with the drives' terms (issue 28): rotor inertia (armature) and friction in the follower's
torque model, against the 1-DOF analytic limit (brute force on the admissible accelerations with friction:
tests/following/test_follower.py), a second
inverse dynamics in joint space (M = CRBA of the links + diag(armature), Pinocchio's nonlinear effects,
friction by hand), and TOPP-RA with armature and Coulomb friction (fs_coef) as the like-for-like bound."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import yaml

from capmap.core.dynamics import payload_models
from capmap.core.limits import AffineLimits
from capmap.core.profiles import scurve
from capmap.core.reduction import free
from capmap.following.follower import FollowSettings, follow
from capmap.following.path import JointPath, path_at
from capmap.following.path_dynamics import path_dynamics, prepare
from capmap.following.tables import follow_path
from capmap.robots import load
from tests.scenario import ROOT

UR5_DRIVES = ROOT / "config" / "robots" / "ur5_drives.yaml"
UR5_Q0 = np.deg2rad([0, -68.75, 91.67, -108.86, -90, 0])
UR5_LIM = np.array([14, 150, 150, 28, 28, 28.0])


@pytest.fixture(scope="module")
def pendulum_on_a_drive(tmp_path_factory):
    """One revolute joint, horizontal axis (gravity along -y), a 4 kg point-like link at r = 0.5 m, on a drive
    of reflected rotor inertia 0.3 kg m^2, Coulomb friction 2 N m, viscous 1.5 N m s/rad."""
    doc = {"name": "pendulum", "dh": {"convention": "modified", "rows": [[0, 0, 0, 0]]},
           "links": [{"mass_kg": 4.0, "com_m": [0.5, 0, 0], "inertia_kgm2": [1e-4, 1e-4, 1e-4]}],
           "joint_range_deg": [[-180, 180]], "gravity_mps2": [0, -9.81, 0],
           "drives": [{"rotor_inertia_kgm2": 3e-5, "gear_ratio": 100, "friction": {"coulomb_nm": 2.0, "viscous_nms": 1.5}}]}
    path = tmp_path_factory.mktemp("robots") / "pendulum.yaml"
    path.write_text(yaml.safe_dump(doc))
    return free(load(path))


def test_one_dof_limited_acceleration_with_rotor_inertia_and_friction_is_the_analytic_value(pendulum_on_a_drive):
    """q(s) = s: tau = (I_o + I_a) sdd + m g r cos s + F_v sd + F_c; at the limit sdd = (T - m g r cos s - F_v sd
    - F_c) / (I_o + I_a), braking at -T likewise: friction helps it."""
    m, r, g, Izz, Ia, Fc, Fv, T = 4.0, 0.5, 9.81, 1e-4, 3e-5 * 100**2, 2.0, 1.5, 25.0
    I = Izz + m * r**2 + Ia
    L = 1.2
    s = np.linspace(0, L, 2401)
    path = JointPath(s=s, q=s[:, None], dq=np.ones((len(s), 1)), ddq=np.zeros((len(s), 1)), p=np.zeros((len(s), 3)))
    pdyn = path_dynamics(pendulum_on_a_drive, path, payload_kg=0.0)
    assert np.allclose(pdyn.a[:, 0], I)  # the armature is in M (Pinocchio's RNEA)
    prep = prepare(pdyn, AffineLimits(np.array([T]), ("tau_j1_nm",)), v_max_mps=20.0)
    res = follow(prep, scurve(L, 20.0, 60.0, 2000.0), period_s=1e-3, catch_up_hz=5.0)
    up, down = res.limited & (res.sdd > 0), res.limited & (res.sdd < 0)
    assert up.sum() > 50
    grav = m * g * r * np.cos(res.s)
    assert np.allclose(res.sdd[up], (T - grav[up] - Fv * res.sd[up] - Fc) / I, rtol=1e-6)
    if down.any():
        assert np.allclose(res.sdd[down], (-T - grav[down] - Fv * res.sd[down] - Fc) / I, rtol=1e-6)
    lo = (-T - grav - Fv * res.sd - Fc) / I
    hi = (T - grav - Fv * res.sd - Fc) / I
    assert np.all(res.sdd >= lo - 1e-6 * np.abs(lo)) and np.all(res.sdd <= hi + 1e-6 * np.abs(hi))
    assert res.s[-1] == pytest.approx(L, abs=1e-5)


def _independent_torques(arm, payload_kg, q, qd, qdd):
    """Motor torques (K, n) by a second formulation: (CRBA of the links, armature zeroed, + diag(armature)) qdd +
    Pinocchio's nonlinear effects (links) + viscous qd + Coulomb sign(qd) (moving states only)."""
    model, _ = payload_models(arm, payload_kg)
    Ia = model.armature.copy()
    model.armature[:] = 0.0
    data = model.createData()
    rob = arm.robot
    out = []
    for k in range(len(q)):
        M = pin.crba(model, data, q[k])
        M = np.triu(M) + np.triu(M, 1).T
        h = pin.nonLinearEffects(model, data, q[k], qd[k])
        out.append((M + np.diag(Ia)) @ qdd[k] + h + rob.viscous_nms * qd[k] + rob.coulomb_nm * np.sign(qd[k]))
    return np.array(out)


@pytest.fixture(scope="module")
def ur5_drives_run():
    arm = free(load(UR5_DRIVES))
    T0 = arm.fk(UR5_Q0[None])[0]
    pts = np.array([T0[:3, 3], T0[:3, 3] + [0, 0.5, 0]])
    st = FollowSettings(2.0, UR5_LIM, 1.0, 4.0, 40.0, 1e-3, 5.0)
    return arm, follow_path(arm, pts, T0[:3, :3], UR5_Q0, st)


def test_the_follower_on_drives_touches_but_never_crosses_the_limit_by_a_second_inverse_dynamics(ur5_drives_run):
    arm, run = ur5_drives_run
    seg = run.followed[0]
    r = seg.result
    moving = r.sd > 1e-6
    pick = np.flatnonzero(moving)[::25]
    # joint states at the follower's (s, sd, sdd) from the exact path (Newton-polished, exact derivatives)
    jp = path_at(arm, seg.table, r.s[pick], arm.fk(UR5_Q0[None])[0][:3, :3])
    qd = jp.dq * r.sd[pick, None]
    qdd = jp.ddq * (r.sd[pick] ** 2)[:, None] + jp.dq * r.sdd[pick, None]
    ref = _independent_torques(arm, 2.0, jp.q, qd, qdd)
    assert np.allclose(seg.tau[pick], ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())
    got = np.abs(seg.tau).max(axis=0) / UR5_LIM
    # the tables are interpolated on a 1 mm grid: 1e-4 of the limit is the same bound as without drives
    assert 0.999 < got[0] <= 1 + 1e-4 and np.all(got <= 1 + 1e-4) and not r.infeasible.any()
    assert np.abs(seg.tau_friction[moving]).max() > 0.25 * UR5_LIM[0]  # friction is a large part at joint 1
    assert abs(r.s[-1] - seg.table.length_m) < 1e-5 and seg.deviation_m.max() < 1e-5


def test_toppra_with_armature_and_coulomb_is_the_like_for_like_bound(ur5_drives_run):
    """TOPP-RA has the armature and Coulomb friction (not viscous): within the limits with those terms, faster
    than the follower without viscous friction (same model, jerk-limited), and over the limit once the viscous
    friction it could not model is counted."""
    arm, run = ur5_drives_run
    c = run.comparison
    assert c.toppra_terms == "links+armature+coulomb" and c.follower_terms == "links+armature+coulomb+viscous"
    assert c.toppra_modelled_peak_torque_pct < 101
    assert c.toppra_duration_s < c.follower_no_viscous_duration_s <= c.follower_duration_s < 1.5 * c.toppra_duration_s
    assert c.follower_no_viscous_peak_torque_pct <= 100.01 and c.follower_max_violation_pct <= 0.01
    assert c.toppra_peak_torque_pct > 100  # viscous friction left out: TOPP-RA's motion needs more than the limit
