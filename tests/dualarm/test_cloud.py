"""The envelope from a point cloud: every point covered, faces where the scene is flat and wide,
capsules on struts and pins, radii set by the noise."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.dualarm.scene.cloud import FitSettings, fit_envelope, min_area_rectangle, uncovered
from capmap.dualarm.scene.solids import Box, Cylinder, PanelSpec, ScanSettings, Scene, scan


def _scene():
    wall = Box("wall", np.array([-0.5, 0.85, -0.5]), np.array([1.5, 0.87, 1.0]))
    block = Box("block", np.array([0.8, -0.2, 0.0]), np.array([1.0, 0.2, 0.4]))
    strut = Cylinder("strut", np.array([0.3, 0.5, -0.5]), np.array([0.3, 0.5, 1.0]), 0.015)
    pin = Cylinder("pin", np.array([0.8, 0.0, 0.2]), np.array([0.72, 0.0, 0.2]), 0.008)
    panel = PanelSpec(np.array([0.012, 0.4, 0.26]), np.zeros((0, 2)), 0.01, np.zeros((2, 3)))
    return Scene("test", (wall, block), (strut, pin), panel, np.eye(4), np.eye(4), np.eye(4), np.zeros(3),
                 np.array([1.0, 0, 0]), np.zeros((2, 3)), np.zeros(14))


@pytest.fixture(scope="module")
def fitted():
    scene = _scene()
    pts, _ = scan(scene, ScanSettings(np.array([[0.0, 0.0, 0.5], [0.2, -0.4, 0.3]]), 0.015, 0.005),
                  np.random.default_rng(0))
    return scene, pts, fit_envelope(pts, FitSettings(), np.random.default_rng(1))


def test_every_point_is_covered(fitted):
    _, pts, env = fitted
    assert len(pts) > 5000 and len(uncovered(pts, env)) == 0


def test_faces_on_wide_planes_capsules_on_struts_and_pins(fitted):
    _, pts, env = fitted
    centres = env.tri.mean(axis=1)
    assert (np.abs(centres[:, 1] - 0.85) < 0.05).any()  # the wall became faces
    assert not (np.hypot(centres[:, 0] - 0.3, centres[:, 1] - 0.5) < 0.05).any()  # no face through the strut
    mids = env.seg.mean(axis=1)
    assert (np.hypot(mids[:, 0] - 0.3, mids[:, 1] - 0.5) < 0.04).any()  # a capsule on the strut
    assert (np.linalg.norm(mids - [0.76, 0.0, 0.2], axis=1) < 0.05).any()  # and one on the pin
    assert 0.01 < env.tri_radius.min() and env.tri_radius.max() < 0.04  # ~ 3 sigma of 5 mm noise plus a margin


def test_radius_covers_without_the_absorbed_tails_leaking(fitted):
    """Removing any face leaves points uncovered: no face is redundant (each was fitted to points)."""
    _, pts, env = fitted
    for k in range(0, len(env.tri), 2):
        keep = np.ones(len(env.tri), dtype=bool)
        keep[k:k + 2] = False
        fewer = type(env)(env.tri[keep], env.tri_radius[keep], env.tri_patch[keep], env.seg, env.seg_radius,
                          env.patch_points, env.seg_points)
        assert len(uncovered(pts, fewer)) > 0


def test_min_area_rectangle_equals_brute_force_rotation():
    rng = np.random.default_rng(3)
    xy = rng.normal(size=(200, 2)) * [1.0, 0.3] @ np.array([[np.cos(0.4), np.sin(0.4)], [-np.sin(0.4), np.cos(0.4)]])
    c = min_area_rectangle(xy)
    u, v = c[1] - c[0], c[3] - c[0]
    area = abs(u[0] * v[1] - u[1] * v[0])
    brute = min(np.prod(np.ptp(xy @ np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]), axis=0))
                for a in np.linspace(0, np.pi / 2, 20001))
    assert area == pytest.approx(brute, rel=1e-4) and area <= brute * (1 + 1e-9)
