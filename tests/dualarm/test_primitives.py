"""Minimum-volume capsules: they cover what they fit, and no capsule found by brute force over
directions and offsets is smaller."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.dualarm.geometry.primitives import box_points, covers, cylinder_points, fit_capsule


def _brute(points, n_dir=40, n_off=9):
    """The smallest covering capsule over a grid of axis directions and offsets (independent)."""
    best = np.inf
    centre = points.mean(axis=0)
    th, ph = np.meshgrid(np.linspace(0, np.pi / 2, n_dir), np.linspace(0, 2 * np.pi, 2 * n_dir, endpoint=False))
    spread = np.abs(points - centre).max()
    for u in np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1).reshape(-1, 3):
        e1 = np.cross(u, [1.0, 0, 0] if abs(u[0]) < 0.9 else [0, 1.0, 0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(u, e1)
        for a in np.linspace(-0.2, 0.2, n_off) * spread:
            for b in np.linspace(-0.2, 0.2, n_off) * spread:
                o = centre + a * e1 + b * e2
                rel = points - o
                t = rel @ u
                rho = np.linalg.norm(rel - np.outer(t, u), axis=1)
                for R in np.linspace(rho.max(), rho.max() + 2 * spread, 30):
                    h = np.sqrt(np.maximum(R * R - rho * rho, 0))
                    L = max((t - h).max() - (t + h).min(), 0.0)
                    best = min(best, np.pi * R * R * L + 4 / 3 * np.pi * R**3)
    return best


@pytest.mark.parametrize("seed", range(2))
def test_capsule_covers_and_is_no_larger_than_brute_force(seed):
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(40, 3)) * rng.uniform(0.02, 0.3, 3) + rng.normal(size=3)
    cap = fit_capsule(pts)
    assert covers(cap, pts).all()
    assert cap.volume <= _brute(pts, n_dir=12, n_off=3) * 1.01


def test_capsule_of_a_cylinder_and_a_box():
    pts = cylinder_points(0.06, 0.136)  # radius 6 cm, 27.2 cm long, rims on circumscribed 24-gons
    cap = fit_capsule(pts)
    assert covers(cap, pts).all()
    # on the cylinder's axis the best capsule trades radius for length: V(R) = pi R^2 (L - 2 h) + 4/3 pi R^3,
    # h = sqrt(R^2 - rc^2), minimised by brute force over R
    rc, L = 0.06 / np.cos(np.pi / 24), 0.272
    R = np.linspace(rc, 0.2, 200001)
    V = np.pi * R**2 * np.maximum(L - 2 * np.sqrt(R**2 - rc**2), 0) + 4 / 3 * np.pi * R**3
    assert cap.volume == pytest.approx(V.min(), rel=1e-3) and cap.r == pytest.approx(R[V.argmin()], rel=1e-2)
    box = box_points(np.array([0.005, 0.0068, 0.056]))  # a finger: long along z
    cap = fit_capsule(box)
    assert covers(cap, box).all() and abs((cap.b - cap.a)[2]) > 0.05


def test_balls_are_covered_with_their_radius():
    c = np.array([[0, 0, 0.0], [0.3, 0, 0]])
    cap = fit_capsule(c, np.array([0.1, 0.05]))
    d = [np.linalg.norm(x - (cap.a + np.clip((x - cap.a) @ (cap.b - cap.a) / ((cap.b - cap.a) @ (cap.b - cap.a)), 0, 1)
                             * (cap.b - cap.a))) for x in c]
    assert d[0] + 0.1 <= cap.r + 1e-9 and d[1] + 0.05 <= cap.r + 1e-9


def test_capsule_of_many_points_covers_them_all_near_the_minimum():
    """Beyond 256 balls the line is searched on a spread subset: every point is still covered, and the
    volume stays within 5 % of the brute-force minimum over lines."""
    rng = np.random.default_rng(7)
    pts = rng.normal(size=(3000, 3)) * [0.05, 0.12, 0.3] + [0.1, -0.2, 0.4]
    cap = fit_capsule(pts)
    assert covers(cap, pts).all()
    assert cap.volume <= _brute(pts, n_dir=12, n_off=3) * 1.05
