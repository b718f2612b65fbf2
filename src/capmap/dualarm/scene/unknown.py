"""Unknown space is not free space: what no camera observed inside the work volume becomes occupied.

A depth camera that returns a point p from its viewpoint v has seen the segment v -> p empty (up to
the point's noise). On a voxel grid over the work volume (a box the user declares: everything the
robot may reach), the voxels that such rays cross, stopping ``stop_m`` short of each point, are
*observed free*; every other voxel is *unknown*: inside solids, behind them from every viewpoint,
out of the cameras' range or view. Unknown voxels wholly inside a fitted volume are left to it. A ray
crossing the corner of a voxel does not see the whole voxel, so a free voxel that touches an unknown one
left over becomes unknown too (the free set eroded by one voxel there): what is unknown then covers every
unobserved part of the scene to within the grid's resolution.

The unknown voxels that the fitted envelope does not already hold are merged into axis-aligned boxes
(greedy runs along x, then y, then z) and each box becomes a swept rectangle: its two largest sides as
a rectangle at mid-thickness, dilated by half its thickness (two triangles and a radius, the volumes
the optimiser already handles), which contains the box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from scipy.ndimage import binary_dilation

from capmap.dualarm.scene.cloud import Envelope

__all__ = ["UnknownSettings", "Grid", "UnknownSpace", "carve", "merge_boxes", "box_rectangles", "unknown_space",
           "near_boxes", "with_boxes"]


@dataclass(frozen=True)
class UnknownSettings:
    """``dualarm.unknown``: the work volume (lower (3,), upper (3,) m), the voxel edge m, and near_m: the
    unknown boxes within it of the motion go to the optimiser (all are checked afterwards)."""

    work_lower: np.ndarray
    work_upper: np.ndarray
    voxel_m: float = 0.02
    near_m: float = 0.1


@dataclass(frozen=True)
class Grid:
    """A voxel grid: lower corner (3,) m, voxel edge m, shape (nx, ny, nz)."""

    lower: np.ndarray
    voxel: float
    shape: tuple[int, int, int]

    @classmethod
    def over(cls, lower, upper, voxel: float) -> "Grid":
        lower, upper = np.asarray(lower, float), np.asarray(upper, float)
        shape = tuple(int(n) for n in np.maximum(np.ceil((upper - lower) / voxel - 1e-9), 1))
        return cls(lower, float(voxel), shape)

    def index(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Voxel indices (n, 3) of points (n, 3) and whether each lies in the grid (n,)."""
        ijk = np.floor((p - self.lower) / self.voxel).astype(np.int64)
        return ijk, np.all((ijk >= 0) & (ijk < np.array(self.shape)), axis=1)

    def centres(self, ijk: np.ndarray) -> np.ndarray:
        return self.lower + (np.asarray(ijk) + 0.5) * self.voxel


@dataclass(frozen=True)
class UnknownSpace:
    """The carving's result: the grid, observed-free voxels (nx, ny, nz) bool, unknown voxels left after
    the envelope's (same shape), and their boxes (B, 2, 3) m [lower, upper]."""

    grid: Grid
    free: np.ndarray
    unknown: np.ndarray
    boxes: np.ndarray


def carve(grid: Grid, points: np.ndarray, seen_from: np.ndarray, stop_m: float, chunk: int = 4096) -> np.ndarray:
    """Observed-free voxels (nx, ny, nz) bool: those the rays from each point's viewpoint ``seen_from``
    (P, 3) m to the point (P, 3) m cross (sampled every half voxel), stopping ``stop_m`` short of the
    point."""
    free = np.zeros(grid.shape, dtype=bool)
    step = grid.voxel / 2
    for s in range(0, len(points), chunk):
        p, v = points[s:s + chunk], seen_from[s:s + chunk]
        d = p - v
        length = np.linalg.norm(d, axis=1)
        reach = np.maximum(length - stop_m, 0.0)
        n = int(np.ceil(reach.max() / step)) + 1 if len(p) else 0
        if n == 0:
            continue
        t = np.arange(n) * step  # (n,)
        ok = t[None, :] <= reach[:, None]  # (c, n)
        u = d / np.maximum(length, 1e-12)[:, None]
        samples = v[:, None, :] + t[None, :, None] * u[:, None, :]  # (c, n, 3)
        ijk, inside = grid.index(samples[ok])
        ijk = ijk[inside]
        free[ijk[:, 0], ijk[:, 1], ijk[:, 2]] = True
    return free


def merge_boxes(need: np.ndarray, allowed: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Axis-aligned boxes of voxels (lower (3,), upper (3,) indices, upper exclusive) that cover every
    voxel of ``need`` and lie inside ``allowed`` (both (nx, ny, nz) bool, need within allowed): greedy,
    from the first voxel still needed, each box grown through allowed voxels along x, then y, then z."""
    left = need.copy()
    nx, ny, nz = need.shape
    out = []
    for i, j, k in zip(*np.nonzero(need)):
        if not left[i, j, k]:
            continue
        i0, i1 = i, i + 1
        while i0 > 0 and allowed[i0 - 1, j, k]:
            i0 -= 1
        while i1 < nx and allowed[i1, j, k]:
            i1 += 1
        j0, j1 = j, j + 1
        while j0 > 0 and allowed[i0:i1, j0 - 1, k].all():
            j0 -= 1
        while j1 < ny and allowed[i0:i1, j1, k].all():
            j1 += 1
        k0, k1 = k, k + 1
        while k0 > 0 and allowed[i0:i1, j0:j1, k0 - 1].all():
            k0 -= 1
        while k1 < nz and allowed[i0:i1, j0:j1, k1].all():
            k1 += 1
        left[i0:i1, j0:j1, k0:k1] = False
        out.append((np.array([i0, j0, k0]), np.array([i1, j1, k1])))
    return out


def _rectangle(lo: np.ndarray, hi: np.ndarray, axis: int, at: float) -> np.ndarray:
    """Two triangles (2, 3, 3) of the rectangle spanning lo..hi across ``axis``, at coordinate ``at`` on it."""
    a, b = [x for x in range(3) if x != axis]
    corners = np.zeros((4, 3))
    for c, (sa, sb) in enumerate(((0, 0), (1, 0), (1, 1), (0, 1))):
        corners[c, a] = hi[a] if sa else lo[a]
        corners[c, b] = hi[b] if sb else lo[b]
        corners[c, axis] = at
    return np.array([corners[[0, 1, 2]], corners[[0, 2, 3]]])


def box_rectangles(boxes: np.ndarray, voxel: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Swept rectangles for boxes (B, 2, 3) m: triangles (T, 3, 3) m, radii (T,) m and the box of each
    (T,). A box at most two
    voxels thick is one rectangle at mid-thickness across its thinnest side, dilated by half that
    thickness (it contains the box, reaching at most a voxel beyond its edges); a thicker box is its six
    faces, each dilated by half a voxel (a shell: a motion that starts outside cannot enter without
    crossing it, and the check afterwards is against every unknown voxel), but for faces wholly against
    other boxes of the same call (inside their union)."""
    tris, radii, owner = [], [], []
    origin = boxes.reshape(-1, 3).min(axis=0) - voxel if len(boxes) else np.zeros(3)
    cells = [(np.round((lo - origin) / voxel).astype(int), np.round((hi - origin) / voxel).astype(int)) for lo, hi in boxes]
    filled = np.zeros(np.max([b for _, b in cells], axis=0) + 1 if cells else (1, 1, 1), dtype=bool)
    for a, b in cells:
        filled[a[0]:b[0], a[1]:b[1], a[2]:b[2]] = True
    for k, ((lo, hi), (a, b)) in enumerate(zip(boxes, cells)):
        size = hi - lo
        thin = int(np.argmin(size))
        if size[thin] <= 2 * voxel + 1e-12:
            tris.append(_rectangle(lo, hi, thin, (lo[thin] + hi[thin]) / 2))
            radii += [size[thin] / 2] * 2
            owner += [k, k]
            continue
        for axis in range(3):
            for side, at in ((0, lo[axis]), (1, hi[axis])):
                layer = [slice(a[i], b[i]) for i in range(3)]  # the cells just outside this face
                layer[axis] = slice(a[axis] - 1, a[axis]) if side == 0 else slice(b[axis], b[axis] + 1)
                if filled[tuple(layer)].all():
                    continue  # inside the union of the boxes: never the first thing a motion from outside meets
                tris.append(_rectangle(lo, hi, axis, at))
                radii += [voxel / 2] * 2
                owner += [k, k]
    return np.concatenate(tris) if tris else np.zeros((0, 3, 3)), np.array(radii), np.array(owner, dtype=int)


def unknown_space(grid: Grid, points: np.ndarray, seen_from: np.ndarray, stop_m: float, covered) -> UnknownSpace:
    """Carve the grid (:func:`carve`), drop the unknown voxels that ``covered`` (a function of voxel
    centres (n, 3) m and a radius m -> bool (n,): the whole voxel inside a fitted volume) already holds,
    take the free voxels that touch what is left as unknown too (a ray that crossed a voxel's corner did
    not see all of it), and merge the unknown voxels into boxes (which may also take in voxels the
    envelope holds)."""
    free = carve(grid, points, seen_from, stop_m)
    half = grid.voxel * np.sqrt(3) / 2

    def uncovered(mask):
        ijk = np.argwhere(mask)
        if len(ijk):
            mask[tuple(ijk[covered(grid.centres(ijk), half)].T)] = False
        return mask

    front = uncovered(~free)
    free &= ~binary_dilation(front, structure=np.ones((3, 3, 3), bool))
    unknown = uncovered(~free)
    boxes = np.array([[grid.lower + lo * grid.voxel, grid.lower + hi * grid.voxel]
                      for lo, hi in merge_boxes(unknown, ~free)])
    return UnknownSpace(grid, free, unknown, boxes.reshape(-1, 2, 3))


def near_boxes(boxes: np.ndarray, points: np.ndarray, radii: np.ndarray, within_m: float) -> np.ndarray:
    """Which boxes (B, 2, 3) m come within ``within_m`` of any ball (points (n, 3) m, radii (n,) m) (B,) bool."""
    if not len(boxes) or not len(points):
        return np.zeros(len(boxes), dtype=bool)
    return _near_boxes(np.ascontiguousarray(boxes, dtype=float), np.ascontiguousarray(points, dtype=float),
                       np.ascontiguousarray(radii, dtype=float), float(within_m))


@numba.njit(cache=True)
def _near_boxes(boxes, points, radii, within):
    """near_boxes, compiled: each box's gap to the balls in turn, up to the first within ``within``."""
    out = np.zeros(boxes.shape[0], np.bool_)
    for b in range(boxes.shape[0]):
        for i in range(points.shape[0]):
            s = 0.0
            for d in range(3):
                g = max(boxes[b, 0, d] - points[i, d], 0.0) + max(points[i, d] - boxes[b, 1, d], 0.0)
                s += g * g
            if np.sqrt(s) - radii[i] <= within:
                out[b] = True
                break
    return out


def with_boxes(env: Envelope, labels: tuple[np.ndarray, np.ndarray], boxes: np.ndarray, voxel: float):
    """The envelope (:class:`capmap.dualarm.scene.cloud.Envelope`) and its labels with boxes (B, 2, 3) m of
    ``voxel`` m voxels added as swept rectangles (:func:`box_rectangles`), labelled
    'unknown [x0 x1, y0 y1, z0 z1]'."""
    tri, r, owner = box_rectangles(boxes, voxel)
    names = np.array([f"unknown [{lo[0]:.2f} {hi[0]:.2f}, {lo[1]:.2f} {hi[1]:.2f}, {lo[2]:.2f} {hi[2]:.2f}]"
                      for lo, hi in boxes], dtype=object)[owner]
    patch = owner + (env.tri_patch.max() + 1 if len(env.tri_patch) else 0)
    out = Envelope(np.concatenate([env.tri, tri]), np.concatenate([env.tri_radius, r]),
                   np.concatenate([env.tri_patch, patch]).astype(int), env.seg, env.seg_radius,
                   np.concatenate([env.patch_points, np.zeros(len(boxes), int)]), env.seg_points)
    return out, (np.concatenate([np.asarray(labels[0], dtype=object), names]), labels[1])
