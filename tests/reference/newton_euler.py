"""An independent reference for the SSRMS-type arm: Craig's modified-DH kinematics and the
textbook recursive Newton-Euler (Craig, ch. 6), written from the robot file's numbers with
no capmap code, so that tests compare capmap against a second formulation."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from tests.scenario import SSRMS_YAML


def rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def spec_table(path=SSRMS_YAML):
    """The DH rows and link data straight from the YAML, SI/radians (independent of capmap)."""
    doc = yaml.safe_load(Path(path).read_text())
    rows = np.array(doc["dh"]["rows"], dtype=float)
    links = [(l["mass_kg"], np.array(l["com_m"], float), np.diag(l["inertia_kgm2"])) for l in doc["links"]]
    return np.deg2rad(rows[:, 0]), rows[:, 1], np.deg2rad(rows[:, 2]), rows[:, 3], links


def craig_step(alpha, a, theta, d):
    """Modified DH: (R, p) of frame i in frame i-1 = Rx(alpha) Tx(a) Rz(theta) Tz(d)."""
    R = rot_x(alpha) @ rot_z(theta)
    p = np.array([a, 0.0, 0.0]) + rot_x(alpha) @ np.array([0.0, 0.0, d])
    return R, p


def craig_fk(q, path=SSRMS_YAML):
    alpha, a, off, d, _ = spec_table(path)
    R, p = np.eye(3), np.zeros(3)
    for i in range(len(q)):
        Ri, pi = craig_step(alpha[i], a[i], q[i] + off[i], d[i])
        p = p + R @ pi
        R = R @ Ri
    return R, p


def newton_euler(q, qd, qdd, gravity, payload_kg=0.0, base_com=np.zeros(3), path=SSRMS_YAML):
    """Textbook recursive Newton-Euler (Craig, ch. 6) for the modified-DH arm.

    Returns joint torques (n,), the EE classical acceleration [a; omega_dot] in the base
    frame (without the gravity trick), and the base disturbance (force, moment about
    base_com) = minus the wrench link 1 receives from the base, in the base frame.
    The payload is a point mass at the EE origin (frame n).
    """
    alpha, a, off, d, links = spec_table(path)
    n = len(q)
    z = np.array([0.0, 0, 1])
    Rs, ps = [], []
    for i in range(n):
        R, p = craig_step(alpha[i], a[i], q[i] + off[i], d[i])
        Rs.append(R)
        ps.append(p)
    w, wd, vd = np.zeros(3), np.zeros(3), -np.asarray(gravity, float)  # gravity trick: base accelerates at -g
    F, N = [], []
    R0 = np.eye(3)
    for i in range(n):
        R, p = Rs[i], ps[i]
        w_new = R.T @ w + qd[i] * z
        wd_new = R.T @ wd + np.cross(R.T @ w, qd[i] * z) + qdd[i] * z
        vd = R.T @ (np.cross(wd, p) + np.cross(w, np.cross(w, p)) + vd)
        w, wd = w_new, wd_new
        m, c, Ic = links[i]
        vdc = np.cross(wd, c) + np.cross(w, np.cross(w, c)) + vd
        F.append(m * vdc)
        N.append(Ic @ wd + np.cross(w, Ic @ w))
        R0 = R0 @ R
    # end-effector frame = frame n (tool offset zero in the spec)
    ee_acc_with_g = vd  # frame n, includes -g
    f = payload_kg * ee_acc_with_g
    nm = np.zeros(3)
    R_next, p_next = np.eye(3), np.zeros(3)
    tau = np.zeros(n)
    for i in reversed(range(n)):
        f_new = R_next @ f + F[i]
        nm = N[i] + R_next @ nm + np.cross(links[i][1], F[i]) + np.cross(p_next, R_next @ f)
        f = f_new
        tau[i] = nm @ z
        R_next, p_next = Rs[i], ps[i]
    # link 1's wrench from the base: force f (frame 1), moment nm about origin 1
    R01, p1 = Rs[0], ps[0]
    Fb = R01 @ f
    Mb_o = R01 @ nm + np.cross(p1, Fb)
    base_force = -Fb
    base_moment = -Mb_o + np.cross(base_com, Fb)
    ee_acc = np.concatenate([R0 @ ee_acc_with_g + np.asarray(gravity, float), R0 @ wd])
    return tau, ee_acc, base_force, base_moment
