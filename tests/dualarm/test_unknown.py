"""Unknown space is occupied (capmap.dualarm.scene.unknown): on the default scene and on a scene with a face no
camera sees, every true surface point of the scene inside the work volume lies in a fitted volume or an
unknown voxel; the boxes cover exactly the unknown voxels; the swept rectangles hold their boxes; the
motion check against unknown voxels agrees with brute force."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

from capmap.config.dualarm import cloud_source, fit_config, unknown_config
from capmap.dualarm.build import fit_settings, scan_settings, unknown_settings
from capmap.dualarm.geometry.distance import segment_triangle
from capmap.dualarm.scene.cloud import depth, fit_envelope
from capmap.dualarm.scene.solids import Box, scan, surface_points
from capmap.dualarm.scene.unknown import Grid, box_rectangles, merge_boxes, near_boxes, unknown_space
from capmap.dualarm.scene.unobserved import swept_balls, unknown_mask, unobserved_check, viewpoints_that_see
from tests.dualarm.conftest import SECTION

HIDDEN = Box("shelf", np.array([0.60, 0.30, 0.45]), np.array([0.70, 0.40, 0.50]))  # under the bulkhead: its top
# face (z = 0.50) faces away from the side cameras (z = 0.2) and the bulkhead hides it from the head camera


def _model(scene):
    _, scan_cfg, seed = cloud_source(SECTION)
    settings = scan_settings(scan_cfg)
    fit_cfg, fit_seed = fit_config(SECTION)

    fit = fit_settings(fit_cfg)
    pts, view = scan(scene, settings, np.random.default_rng(seed))
    env = fit_envelope(pts, fit, np.random.default_rng(fit_seed))
    u = unknown_settings(unknown_config(SECTION))
    grid = Grid.over(u.work_lower, u.work_upper, u.voxel_m)
    space = unknown_space(grid, pts, settings.viewpoints[view], 3 * settings.noise_m, lambda c, r: depth(c, env) <= -r)
    return pts, view, env, space


def _uncovered_surface(scene, env, space, owner_name=None):
    """True surface points (1 cm apart) inside the work volume that lie in no fitted volume and in no
    unknown voxel (nor in a voxel of a box: the boxes may take in voxels the envelope holds)."""
    surf, _, owner = surface_points(scene, 0.01)
    g = space.grid
    ijk, inside = g.index(surf)
    names = np.array([s.name for s in (*scene.boxes, *scene.cylinders)])
    keep = inside if owner_name is None else inside & (names[owner] == owner_name)
    surf, ijk = surf[keep], ijk[keep]
    occupied = unknown_mask(g, space.boxes)[tuple(ijk.T)]
    fitted = depth(surf, env) <= 1e-9
    return surf[~(occupied | fitted)], surf, fitted


@pytest.fixture(scope="module")
def default(scene):
    return _model(scene)


@pytest.fixture(scope="module")
def hidden(scene):
    s = replace(scene, boxes=scene.boxes + (HIDDEN,))
    return s, _model(s)


def test_every_surface_in_the_work_volume_is_fitted_or_unknown(scene, default):
    _, _, env, space = default
    bad, surf, _ = _uncovered_surface(scene, env, space)
    assert len(surf) > 50_000 and len(bad) == 0, bad[:5]


def test_a_face_no_camera_sees_is_held_by_unknown_space(hidden):
    scene, (pts, view, env, space) = hidden
    _, scan_cfg, _ = cloud_source(SECTION)
    settings = scan_settings(scan_cfg)
    exact, _ = scan(scene, replace(settings, noise_m=0.0), np.random.default_rng(0))  # the same scan without noise
    top = np.abs(exact[:, 2] - 0.50) < 1e-9
    over = (exact[:, 0] > 0.6) & (exact[:, 0] < 0.7) & (exact[:, 1] > 0.3) & (exact[:, 1] < 0.4)
    assert not (top & over).any()  # no camera saw the shelf's top face
    bad, surf, fitted = _uncovered_surface(scene, env, space, "shelf")
    assert len(bad) == 0, bad[:5]
    assert not fitted.all()  # the fit alone leaves part of the shelf out: unknown space holds it


def test_boxes_are_exactly_the_needed_voxels_within_the_allowed():
    rng = np.random.default_rng(2)
    for _ in range(5):
        allowed = rng.random((9, 8, 7)) < 0.7
        need = allowed & (rng.random(allowed.shape) < 0.4)
        cover = np.zeros_like(need)
        for lo, hi in merge_boxes(need, allowed):
            block = (slice(lo[0], hi[0]), slice(lo[1], hi[1]), slice(lo[2], hi[2]))
            assert allowed[block].all()
            cover[block] = True
        assert (cover >= need).all()


def test_swept_rectangles_hold_their_boxes():
    rng = np.random.default_rng(4)
    voxel = 0.02
    boxes = np.array([[[0, 0, 0], [0.2, 0.1, 0.04]], [[0.1, -0.3, 0.2], [0.3, -0.1, 0.6]], [[0, 0, 0], [0.02, 0.02, 0.02]]])
    for box in boxes:
        tri, r, _ = box_rectangles(box[None], voxel)
        pts = box[0] + rng.random((3000, 3)) * (box[1] - box[0])
        if (box[1] - box[0]).min() > 2 * voxel:  # a shell: test the surface
            axis = rng.integers(0, 3, len(pts))
            pts[np.arange(len(pts)), axis] = np.where(rng.random(len(pts)) < 0.5, box[0][axis], box[1][axis])
        d = np.full(len(pts), np.inf)
        for t, rt in zip(tri, r):
            v = np.broadcast_to(t, (len(pts), 3, 3))
            d = np.minimum(d, segment_triangle(pts, pts, v[:, 0], v[:, 1], v[:, 2]).distance - rt)
        assert d.max() <= 1e-9


@pytest.mark.parametrize("seed, near", [(6, 0.0), (7, 0.06), (8, 0.07), (9, 0.08)])
def test_the_motion_check_is_a_lower_bound_of_the_brute_force_distance(seed, near):
    """Balls anywhere in the work volume (near 0) or within ``near`` m of the first box's faces (where the
    exact distance is taken: the least distance is under 1 cm)."""
    rng = np.random.default_rng(seed)
    grid = Grid.over([0, 0, 0], [0.4, 0.4, 0.4], 0.02)
    boxes = np.array([[[0.1, 0.1, 0.1], [0.16, 0.3, 0.2]], [[0.3, 0.0, 0.3], [0.4, 0.08, 0.4]]])
    mask = unknown_mask(grid, boxes)
    lo, hi = (boxes[0, 0] - near, boxes[0, 1] + near) if near else (np.zeros(3), np.full(3, 0.4))
    balls = rng.uniform(lo, hi, (40, 12, 3))
    if near:  # outside the box: pushed out along the axis of the least penetration
        inside = np.all((balls > boxes[0, 0]) & (balls < boxes[0, 1]), axis=2)
        balls[inside] = boxes[0, 0] - 0.061
    radii = rng.uniform(0.01, 0.05, 12)
    check = unobserved_check(balls, radii, np.array(["b"] * 12, dtype=object), grid, mask)
    out = np.maximum(np.maximum(boxes[None, :, 0] - balls.reshape(-1, 1, 3), balls.reshape(-1, 1, 3) - boxes[None, :, 1]),
                     0)
    brute = (np.linalg.norm(out, axis=2).min(axis=1) - np.tile(radii, 40)).min()
    assert check.distance <= brute + 1e-12
    assert check.distance >= brute - 0.02 * np.sqrt(3) - 1e-12  # at most a voxel diagonal below
    if brute < 0.01:
        assert check.distance == pytest.approx(brute, abs=1e-12)  # exact where it matters
    assert brute < 0.01 or not near


def test_swept_balls_with_their_slack_hold_the_whole_volumes(robot, scene, make_assembly):
    """Points drawn inside every arm capsule and inside the panel's slab, at a random configuration, each
    lie within radius + slack of some ball: the check's distances bound the volumes, not only the balls."""
    asm = make_assembly(20, 0.05, 14)
    rng = np.random.default_rng(8)
    q = asm.q_start + rng.uniform(-0.2, 0.2, asm.model.nq)
    balls, radii, names, slack = swept_balls(asm, robot, scene.panel.corners(), q[None])
    data = asm.model.createData()
    pin.forwardKinematics(asm.model, data, q)
    pin.updateFramePlacements(asm.model, data)
    pts = []
    for c in robot.capsules:
        if c.part == "body":
            continue
        M = data.oMi[asm.model.getJointId(c.joint)]
        t = rng.random(300)[:, None]
        d = rng.normal(size=(300, 3))
        d *= (c.r * rng.random(300) ** (1 / 3) / np.linalg.norm(d, axis=1))[:, None]
        pts.append((c.a + t * (c.b - c.a) + d) @ M.rotation.T + M.translation)
    corners = scene.panel.corners()
    u, v, w = rng.random((3, 2000))
    local = corners[0] + u[:, None] * (corners[1] - corners[0]) + v[:, None] * (corners[3] - corners[0])
    local[:, 0] += (2 * w - 1) * asm.panel_radius  # through the panel's thickness
    Mp = data.oMf[asm.task.panel]
    pts.append(local @ Mp.rotation.T + Mp.translation)
    pts = np.concatenate(pts)
    reach = np.linalg.norm(pts[:, None, :] - balls[0][None], axis=2) - (radii + slack)[None]
    assert reach.min(axis=1).max() <= 1e-12


def test_suggested_viewpoints_see_the_region_past_every_obstacle():
    """An unknown box behind a wall (a fitted volume) and another unknown box: every suggested camera's
    segment to the region's centre, sampled densely here, crosses no unknown voxel and no fitted volume
    before it enters the region, and cameras behind the wall are not suggested."""
    grid = Grid.over([0, 0, 0], [1, 1, 1], 0.02)
    region = np.array([[0.7, 0.4, 0.4], [0.8, 0.6, 0.6]])
    other = np.array([[0.3, 0.0, 0.0], [0.4, 1.0, 0.5]])  # an unknown slab across the lower half
    mask = unknown_mask(grid, np.array([region, other]))

    def depth_fn(p):  # a fitted wall x in [0.5, 0.52], y < 0.3 (a slab of radius 1 cm about x = 0.51)
        return np.where(p[:, 1] < 0.3, np.abs(p[:, 0] - 0.51) - 0.01, 1.0)

    seen = viewpoints_that_see(region, grid, mask, depth_fn, np.array([0.1, 0.5, 0.9]), n=600)
    assert len(seen) > 5
    target = region.mean(axis=0)
    for c in seen:
        t = np.linspace(0, 1, 2000)[:, None]
        pts = c + t * (target - c)
        pts = pts[~np.all((pts >= region[0]) & (pts <= region[1]), axis=1)]
        assert (depth_fn(pts) > 0).all()
        assert not np.any(np.all((pts >= other[0]) & (pts <= other[1]), axis=1))


def test_near_boxes_equal_every_ball_against_every_box():
    """The boxes near a set of balls (a k-d tree's candidates, then the exact gap) against every ball's gap to
    every box, with balls placed just inside and just outside the distance."""
    rng = np.random.default_rng(21)
    lo = rng.uniform(-1, 1, (60, 3))
    boxes = np.stack([lo, lo + rng.uniform(0.02, 0.3, (60, 3))], axis=1)
    pts, radii = rng.uniform(-1.3, 1.5, (3000, 3)), rng.uniform(0.0, 0.08, 3000)
    gap = (np.maximum(boxes[None, :, 0] - pts[:, None], 0) + np.maximum(pts[:, None] - boxes[None, :, 1], 0))
    dist = np.linalg.norm(gap, axis=2) - radii[:, None]  # (balls, boxes)
    for within in (0.0, 0.05, 0.1):
        expect = (dist <= within).any(axis=0)
        assert np.array_equal(near_boxes(boxes, pts, radii, within), expect)
        assert 0 < expect.sum() < len(boxes)
    assert not near_boxes(boxes, pts[:0], radii[:0], 0.1).any()
