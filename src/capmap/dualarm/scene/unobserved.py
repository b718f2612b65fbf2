"""The motion against the space no camera observed (:mod:`capmap.dualarm.scene.unknown`): which unknown boxes
the optimiser must see (those near the moving volumes), and the check afterwards against all of them.

The moving volumes (every arm capsule and the held panel) are sampled as balls: each capsule at
``spacing`` along its segment, the panel's rectangle on a grid of ``spacing`` with its half-thickness as
radius. A point of a volume lies within sqrt(h^2 + r^2) of a ball's centre (h: half the samples' spacing
along a segment, half their diagonal on the panel), so each ball carries the slack sqrt(h^2 + r^2) - r
that the check subtracts: its distances are lower bounds for the whole volumes, not only the balls."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numba
import numpy as np
import pinocchio as pin
from scipy.ndimage import distance_transform_edt

from capmap.dualarm.geometry.chain import joint_placements, pack
from capmap.dualarm.ocp.assembly import Assembly
from capmap.dualarm.scene.cloud import Envelope, depth
from capmap.dualarm.scene.robot import DualArm
from capmap.dualarm.scene.unknown import Grid, UnknownSettings

__all__ = ["swept_balls", "UnobservedCheck", "unobserved_check", "unknown_mask", "viewpoints_that_see",
           "camera_suggestion"]


def swept_balls(asm: Assembly, robot: DualArm, panel_corners: np.ndarray, qs: np.ndarray,
                spacing: float = 0.02) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Balls sampling the arms' capsules and the panel at configurations qs (K, nq): centres (K, n, 3) m,
    radii (n,) m, their bodies' names (n,) and each ball's slack (n,) m (see the module docstring)."""
    model = asm.model
    caps = [c for c in robot.capsules if c.part != "body"]
    local, radii, names, joints, slack = [], [], [], [], []
    for c in caps:
        length = float(np.linalg.norm(c.b - c.a))
        n = max(2, int(np.ceil(length / spacing)) + 1)
        t = np.linspace(0, 1, n)[:, None]
        local.append(c.a + t * (c.b - c.a))
        radii += [c.r] * n
        names += [c.name] * n
        joints += [model.getJointId(c.joint)] * n
        h = length / (n - 1) / 2
        slack += [np.hypot(h, c.r) - c.r] * n
    fp = model.frames[asm.task.panel]
    a, b = panel_corners[1] - panel_corners[0], panel_corners[3] - panel_corners[0]
    nu, nv = (max(2, int(np.ceil(np.linalg.norm(x) / spacing)) + 1) for x in (a, b))
    u, v = np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv), indexing="ij")
    grid = panel_corners[0] + u.reshape(-1, 1) * a + v.reshape(-1, 1) * b  # panel frame
    local.append(grid @ fp.placement.rotation.T + fp.placement.translation)  # its joint's frame
    radii += [asm.panel_radius] * len(grid)
    names += ["panel"] * len(grid)
    joints += [fp.parentJoint] * len(grid)
    h = 0.5 * np.hypot(np.linalg.norm(a) / (nu - 1), np.linalg.norm(b) / (nv - 1))
    slack += [np.hypot(h, asm.panel_radius) - asm.panel_radius] * len(grid)
    local, joints = np.concatenate(local), np.asarray(joints)
    used = np.unique(joints)
    t = asm.task
    packed = pack(model, (t.left, t.right, t.panel), asm.collision.prims)
    qs = np.ascontiguousarray(qs, dtype=float)
    R, p = np.empty((len(qs), model.njoints, 3, 3)), np.empty((len(qs), model.njoints, 3))
    if isinstance(packed, str):  # Pinocchio's placements
        data = model.createData()
        for k, q in enumerate(qs):
            pin.forwardKinematics(model, data, q)
            for j in used:
                R[k, j], p[k, j] = data.oMi[int(j)].rotation, data.oMi[int(j)].translation
    else:  # the packed chain's, compiled (equal to Pinocchio's in tests/dualarm/test_nodes.py)
        joint_placements(packed.chain_f, packed.chain_i, qs, R, p)
    out = np.empty((len(qs), len(local), 3))
    for j in used:
        sel = joints == j
        out[:, sel] = local[sel] @ R[:, j].transpose(0, 2, 1) + p[:, j, None, :]
    return out, np.asarray(radii), np.asarray(names, dtype=object), np.asarray(slack)


@numba.njit(cache=True)
def _bound_gaps(pts, radii, slack, lower, voxel, edt, beyond):
    """Per ball centre pts (M, 3) m (ball i has radius radii[i % n] and slack slack[i % n], m): the
    transform's bound on its gap to unknown space, edt (the distance in voxels from each voxel to the nearest
    unknown voxel centre) x voxel - a voxel diagonal - radius, at most ``beyond`` (``beyond`` outside the
    grid), less the slack; and its voxel (M, 3), clipped to the grid. The arithmetic of numpy's
    edt[ijk] * voxel - voxel sqrt(3) - r, term for term."""
    M, n = pts.shape[0], radii.shape[0]
    gap, ijk = np.empty(M), np.empty((M, 3), np.int64)
    diag = voxel * np.sqrt(3.0)
    for m in range(M):
        inside = True
        for a in range(3):
            v = np.int64(np.floor((pts[m, a] - lower[a]) / voxel))
            if v < 0 or v >= edt.shape[a]:
                inside = False
            ijk[m, a] = min(max(v, 0), edt.shape[a] - 1)
        g = beyond
        if inside:
            g = min(edt[ijk[m, 0], ijk[m, 1], ijk[m, 2]] * voxel - diag - radii[m % n], beyond)
        gap[m] = g - slack[m % n]
    return gap, ijk


@numba.njit(cache=True)
def _cube_distances(pts, near, reach, ijk, mask, lower, voxel):
    """For each ball centre pts[near[n]] (m): the distance (m) to the nearest unknown voxel of ``mask`` (a cube
    of side ``voxel`` m) within reach[n] voxels of its voxel ijk[near[n]]; inf when none."""
    out = np.full(len(near), np.inf)
    for n in range(len(near)):
        c = near[n]
        lo = np.maximum(ijk[c] - reach[n], 0)
        hi = np.minimum(ijk[c] + reach[n] + 1, np.array(mask.shape))
        for i in range(lo[0], hi[0]):
            for j in range(lo[1], hi[1]):
                for k in range(lo[2], hi[2]):
                    if mask[i, j, k]:
                        dx = max(abs(pts[c, 0] - (lower[0] + (i + 0.5) * voxel)) - voxel / 2, 0.0)
                        dy = max(abs(pts[c, 1] - (lower[1] + (j + 0.5) * voxel)) - voxel / 2, 0.0)
                        dz = max(abs(pts[c, 2] - (lower[2] + (k + 0.5) * voxel)) - voxel / 2, 0.0)
                        out[n] = min(out[n], np.sqrt(dx * dx + dy * dy + dz * dz))
    return out


def unknown_mask(grid: Grid, boxes: np.ndarray) -> np.ndarray:
    """The voxels (nx, ny, nz) bool of ``grid`` that boxes (B, 2, 3) m (made of its voxels) fill."""
    mask = np.zeros(grid.shape, dtype=bool)
    for lo, hi in boxes:
        a = np.round((lo - grid.lower) / grid.voxel).astype(int)
        b = np.round((hi - grid.lower) / grid.voxel).astype(int)
        mask[a[0]:b[0], a[1]:b[1], a[2]:b[2]] = True
    return mask


@dataclass(frozen=True)
class UnobservedCheck:
    """The smallest distance (m) from the moving volumes to unknown space over the samples (a voxel taken
    as its circumscribed ball: conservative by up to half a voxel diagonal), where (sample index), which
    body, and the unknown voxel's centre (3,) m (sample -1: none nearer than the bound reported)."""

    distance: float
    sample: int
    body: str
    voxel_centre: np.ndarray


def unobserved_check(balls: np.ndarray, radii: np.ndarray, names: np.ndarray, grid: Grid, mask: np.ndarray,
                     beyond_m: float = 0.3, slack: np.ndarray | None = None) -> UnobservedCheck:
    """:class:`UnobservedCheck` of balls (K, n, 3) m with radii (n,) against the unknown voxels ``mask`` of
    ``grid``: the Euclidean distance transform gives each voxel's distance to the nearest unknown voxel
    centre; a ball centre lies within half a voxel diagonal of its voxel's centre and an unknown voxel
    reaches half a diagonal beyond its own, so the gap is at least that distance - a diagonal - the
    radius; where that bound is under 1 cm, the exact distance from the ball to the unknown cubes around
    it is taken. Distances of ``beyond_m`` or more are reported as beyond_m; outside the grid (the work
    volume) nothing is modelled. ``slack`` (n,): each ball's, subtracted (:func:`swept_balls`)."""
    if not mask.any():
        return UnobservedCheck(beyond_m, -1, "", np.full(3, np.nan))
    edt, nearest = distance_transform_edt(~mask, return_indices=True)
    pts = np.ascontiguousarray(balls, dtype=float).reshape(-1, 3)
    sl = np.zeros(len(radii)) if slack is None else np.asarray(slack, dtype=float)
    gap, ijk = _bound_gaps(pts, np.asarray(radii, dtype=float), sl, np.asarray(grid.lower, float), float(grid.voxel),
                           edt, float(beyond_m))
    # where the bound is small, the exact distance to the unknown voxels (cubes) around the ball
    near = np.flatnonzero(gap < 0.01)
    r_near, s_near = np.asarray(radii, dtype=float)[near % len(radii)], sl[near % len(radii)]  # ball i: body i % n
    reach = (np.ceil((r_near + 0.01) / grid.voxel)).astype(np.int64) + 1
    exact = _cube_distances(pts, near, reach, ijk, mask, np.asarray(grid.lower, float), float(grid.voxel))
    gap[near] = np.where(np.isfinite(exact), exact - (r_near + s_near), min(0.01, beyond_m))
    i = int(np.argmin(gap))
    if not gap[i] < beyond_m:
        return UnobservedCheck(beyond_m, -1, "", np.full(3, np.nan))
    at = tuple(nearest[(slice(None), *ijk[i])])
    return UnobservedCheck(float(gap[i]), i // balls.shape[1], str(names[i % balls.shape[1]]), grid.centres(np.array(at)))


def viewpoints_that_see(region: np.ndarray, grid: Grid, mask: np.ndarray, depth_fn, around: np.ndarray,
                        n: int = 400, rng: np.random.Generator | None = None) -> np.ndarray:
    """Camera positions (k, 3) m, nearest ``around`` (3,) m first, from which the centre of an unknown
    ``region`` (2, 3) m is in sight: every point of the segment before it enters the region lies in no
    unknown voxel of ``mask`` and outside every fitted volume (``depth_fn``: points (m, 3) -> depth (m,),
    > 0 outside). Candidates: ``n`` points of the work volume in the open (depth > 5 cm, not unknown)."""
    rng = np.random.default_rng(0) if rng is None else rng
    hi = grid.lower + np.array(grid.shape) * grid.voxel
    cand = rng.uniform(grid.lower, hi, (n, 3))
    ijk, _ = grid.index(cand)
    ijk = np.clip(ijk, 0, np.array(grid.shape) - 1)
    cand = cand[~mask[tuple(ijk.T)] & (depth_fn(cand) > 0.05)]
    target = region.mean(axis=0)
    ok = []
    for c in cand:
        d = target - c
        pts = c + np.outer(np.arange(0.0, 1.0, grid.voxel / 2 / max(np.linalg.norm(d), 1e-9)), d)
        pts = pts[~np.all((pts >= region[0]) & (pts <= region[1]), axis=1)]
        ijk, inside = grid.index(pts)
        if not inside.all() or mask[tuple(ijk.T)].any() or (depth_fn(pts) <= 0).any():
            continue
        ok.append(c)
    ok = np.array(ok).reshape(-1, 3)
    return ok[np.argsort(np.linalg.norm(ok - around, axis=1))]


def camera_suggestion(msg: str, u: UnknownSettings, env: Envelope, boxes: np.ndarray, around: np.ndarray) -> str:
    """Where a camera would see the unknown region named in ``msg`` ('unknown [x0 x1, y0 y1, z0 z1]', m): the
    candidates of :func:`viewpoints_that_see` nearest ``around`` (3,) m (the configured viewpoints' mean), in the
    work volume of ``u`` with the unknown boxes (B, 2, 3) m and the fitted envelope ``env`` in the way."""
    x = [float(v) for v in re.search(r"unknown \[([-\d.]+) ([-\d.]+), ([-\d.]+) ([-\d.]+), ([-\d.]+) ([-\d.]+)\]",
                                     msg).groups()]
    region = np.array([[x[0], x[2], x[4]], [x[1], x[3], x[5]]])
    grid = Grid.over(u.work_lower, u.work_upper, u.voxel_m)
    seen = viewpoints_that_see(region, grid, unknown_mask(grid, boxes), lambda p: depth(p, env), around)
    if not len(seen):
        return "no point of the work volume in the open has a line of sight to it"
    return "a camera at " + " or ".join(str(np.round(v, 2).tolist()) for v in seen[:2]) + " m would see it"
