"""A safety envelope from a point cloud: swept triangles on the flat parts, capsules on the rest.

1. Per-point normals by PCA over the k nearest neighbours.
2. Planes by RANSAC (three points, inliers within ``plane_tol_m`` whose normals agree within
   ``normal_tol_deg``), refined by least squares; a plane's inliers are split into connected
   patches on an in-plane grid, and a patch is kept only if it is flat and filled (its
   occupied cells cover ``min_fill`` of its minimum-area rectangle), else a 'plane' would run
   through a thin strip and a strut. Each kept patch becomes its minimum-area rectangle (two
   triangles) whose radius covers the patch's points plus ``margin_m``; points near the
   rectangle that the noise spread beyond the inlier band are absorbed into it (else they
   would become hundreds of tiny capsules).
3. What is left is split into connected clusters, each covered by a capsule on its principal
   axis; a capsule fatter than ``max_capsule_radius_m`` is split in two by k-means.
4. Every point must lie inside some volume (:func:`uncovered`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError, cKDTree

from capmap.dualarm.geometry.distance import segment_segment, segment_triangle
from capmap.errors import CapmapError

__all__ = ["FitSettings", "Envelope", "fit_envelope", "grow_to_cover", "normals", "min_area_rectangle", "uncovered",
           "depth", "radius_span"]


@dataclass(frozen=True)
class FitSettings:
    """Fitting parameters (see the module docstring); ``min_patch_points``: the smallest plane patch;
    ``min_width_m``: the narrowest face (narrower strips are left to capsules); ``absorb``: the
    band, in plane tolerances, within which unclaimed points over a face join it; ``thin_m``: the fit
    sees one point per cell of this size (a multi-camera cloud holds a surface once per camera), then
    every volume's radius grows to hold the points it is nearest to that it left out."""

    plane_tol_m: float = 0.02
    normal_tol_deg: float = 25.0
    neighbours: int = 16
    cell_m: float = 0.04
    min_fill: float = 0.6
    min_width_m: float = 0.1
    absorb: float = 1.5
    min_patch_points: int = 40
    margin_m: float = 0.002
    max_capsule_radius_m: float = 0.04
    ransac_iterations: int = 400
    thin_m: float = 0.015


@dataclass(frozen=True)
class Envelope:
    """Swept triangles: tri (T, 3, 3) m, tri_radius (T,) m, tri_patch (T,) the patch each came
    from (two per rectangle); capsules: seg (S, 2, 3) m, seg_radius (S,) m; and how many cloud
    points each patch / capsule was fitted to."""

    tri: np.ndarray
    tri_radius: np.ndarray
    tri_patch: np.ndarray
    seg: np.ndarray
    seg_radius: np.ndarray
    patch_points: np.ndarray
    seg_points: np.ndarray


def normals(points: np.ndarray, k: int) -> np.ndarray:
    """Unit normals (P, 3): the least-variance direction of each point's k nearest neighbours."""
    _, idx = cKDTree(points).query(points, k=min(k, len(points)))
    nb = points[idx] - points[idx].mean(axis=1, keepdims=True)
    cov = np.einsum("pki,pkj->pij", nb, nb)
    return np.linalg.eigh(cov)[1][:, :, 0]


def min_area_rectangle(xy: np.ndarray) -> np.ndarray:
    """Corners (4, 2) of the minimum-area rectangle holding 2-D points (n, 2) (an edge of the convex
    hull lies on a side of it), in order around the rectangle."""
    try:
        hull = xy[ConvexHull(xy).vertices]
    except QhullError:
        hull = xy
    edges = np.diff(np.vstack([hull, hull[:1]]), axis=0)
    angles = np.unique(np.mod(np.arctan2(edges[:, 1], edges[:, 0]), np.pi / 2))
    best = None
    for a in angles:
        R = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
        p = hull @ R.T
        lo, hi = p.min(axis=0), p.max(axis=0)
        area = float(np.prod(hi - lo))
        if best is None or area < best[0]:
            corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
            best = (area, corners @ R)
    return best[1]


def _plane_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(n, h)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def _ransac_plane(p, nrm, st, rng):
    """The plane (point, normal) with the most inliers among random three-point planes; its inliers."""
    cos_tol = np.cos(np.deg2rad(st.normal_tol_deg))
    best, best_in = None, None
    for _ in range(st.ransac_iterations):
        a, b, c = p[rng.choice(len(p), 3, replace=False)]
        n = np.cross(b - a, c - a)
        if np.linalg.norm(n) < 1e-9:
            continue
        n /= np.linalg.norm(n)
        inl = (np.abs((p - a) @ n) < st.plane_tol_m) & (np.abs(nrm @ n) > cos_tol)
        if best_in is None or inl.sum() > best_in.sum():
            best, best_in = (a, n), inl
    if best is None:
        return None, None
    centre = p[best_in].mean(axis=0)  # least-squares refit
    n = np.linalg.svd(p[best_in] - centre, full_matrices=False)[2][-1]
    inl = (np.abs((p - centre) @ n) < st.plane_tol_m) & (np.abs(nrm @ n) > cos_tol)
    return (centre, n), inl


def _patches(xy: np.ndarray, cell: float) -> np.ndarray:
    """Connected patches of 2-D points on a grid of ``cell`` (8-connected occupied cells): labels (n,)."""
    ij = np.floor((xy - xy.min(axis=0)) / cell).astype(int)
    grid = np.zeros(ij.max(axis=0) + 1, dtype=bool)
    grid[ij[:, 0], ij[:, 1]] = True
    from scipy.ndimage import label  # here, as kmeans2

    lab, _ = label(grid, structure=np.ones((3, 3)))
    return lab[ij[:, 0], ij[:, 1]]


def _capsules(p: np.ndarray, st: FitSettings, rng) -> list[tuple[np.ndarray, np.ndarray, float, int]]:
    """Capsules (a, b, r, n_points) covering a cluster, split by k-means while fatter than allowed."""
    centre = p.mean(axis=0)
    axis = np.linalg.svd(p - centre, full_matrices=False)[2][0] if len(p) > 1 else np.array([1.0, 0, 0])
    t = (p - centre) @ axis
    a, b = centre + t.min() * axis, centre + t.max() * axis
    tt = np.clip(t, t.min(), t.max())
    r = float(np.linalg.norm(p - centre - np.outer(tt, axis), axis=1).max()) + st.margin_m
    if r <= st.max_capsule_radius_m or len(p) < 8:
        return [(a, b, r, len(p))]
    from scipy.cluster.vq import kmeans2  # here: scipy.cluster costs 0.17 s to import, in every job reading the config

    _, lab = kmeans2(p, 2, seed=rng, minit="++")
    if lab.min() == lab.max():
        return [(a, b, r, len(p))]
    return _capsules(p[lab == 0], st, rng) + _capsules(p[lab == 1], st, rng)


def fit_envelope(points: np.ndarray, st: FitSettings, rng: np.random.Generator) -> Envelope:
    """Swept triangles and capsules covering every point of a cloud (P, 3) m: fitted to one point per
    cell of ``st.thin_m``, then grown to hold them all (:func:`grow_to_cover`)."""
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 10:
        raise CapmapError(f"a cloud needs at least 10 points of shape (n, 3), got {points.shape}")
    _, first = np.unique(np.floor(points / st.thin_m).astype(np.int64), axis=0, return_index=True)
    kept = points[np.sort(first)]
    return grow_to_cover(_fit(kept if len(kept) >= 10 else points, st, rng), points)


def grow_to_cover(env: Envelope, points: np.ndarray) -> Envelope:
    """The envelope with each volume's radius grown to hold the points (P, 3) m it is nearest to and does
    not hold (a face's two triangles together)."""
    left = uncovered(points, env)
    if not len(left):
        return env
    p = points[left]
    d = np.full((len(p), len(env.tri) + len(env.seg)), np.inf)
    for k in range(len(env.tri)):
        v = np.broadcast_to(env.tri[k], (len(p), 3, 3))
        d[:, k] = segment_triangle(p, p, v[:, 0], v[:, 1], v[:, 2]).distance
    for k in range(len(env.seg)):
        sg = np.broadcast_to(env.seg[k], (len(p), 2, 3))
        d[:, len(env.tri) + k] = segment_segment(p, p, sg[:, 0], sg[:, 1]).distance
    radius = np.concatenate([env.tri_radius, env.seg_radius])
    best = np.argmin(d - radius, axis=1)
    grow = radius.copy()
    np.maximum.at(grow, best, d[np.arange(len(p)), best] + 1e-9)
    tri_r = grow[:len(env.tri)]
    for patch in np.unique(env.tri_patch):  # a face's triangles keep one radius
        sel = env.tri_patch == patch
        tri_r[sel] = tri_r[sel].max()
    return Envelope(env.tri, tri_r, env.tri_patch, env.seg, grow[len(env.tri):], env.patch_points, env.seg_points)


def _fit(points: np.ndarray, st: FitSettings, rng: np.random.Generator) -> Envelope:
    nrm = normals(points, st.neighbours)
    left = np.ones(len(points), dtype=bool)
    plane_ok = np.ones(len(points), dtype=bool)  # points a plane may still take
    tris, radii, tri_patch, patch_points = [], [], [], []
    while (left & plane_ok).sum() >= st.min_patch_points:
        idx = np.flatnonzero(left & plane_ok)
        plane, inl = _ransac_plane(points[idx], nrm[idx], st, rng)
        if plane is None or inl.sum() < st.min_patch_points:
            break
        centre, n = plane
        e1, e2 = _plane_basis(n)
        members = idx[inl]
        xy = np.column_stack([(points[members] - centre) @ e1, (points[members] - centre) @ e2])
        labels = _patches(xy, st.cell_m)
        kept = False
        for lab in np.unique(labels):
            sel = labels == lab
            if sel.sum() < st.min_patch_points:
                continue
            corners2 = min_area_rectangle(xy[sel])
            sides = np.linalg.norm(corners2[[1, 3]] - corners2[0], axis=1)
            cells = np.unique(np.floor(xy[sel] / st.cell_m).astype(int), axis=0)
            if sides.min() < st.min_width_m or len(cells) * st.cell_m**2 < st.min_fill * sides.prod():
                continue  # a thin strip (a strut seen side-on), or a plane through scattered parts: not a face
            corners = centre + corners2[:, :1] * e1 + corners2[:, 1:] * e2
            # absorb the noise tails: unclaimed points over the rectangle, within the absorbing band
            rel = points[left] - centre
            near = (_rectangle_distance(np.column_stack([rel @ e1, rel @ e2]), rel @ n, corners2)
                    < st.absorb * st.plane_tol_m)
            took = np.union1d(members[sel], np.flatnonzero(left)[near])
            rel = points[took] - centre
            r = float(_rectangle_distance(np.column_stack([rel @ e1, rel @ e2]), rel @ n, corners2).max()) + st.margin_m
            k = len(patch_points)
            tris += [corners[[0, 1, 2]], corners[[0, 2, 3]]]
            radii += [r, r]
            tri_patch += [k, k]
            patch_points.append(len(took))
            left[took] = False
            kept = True
        if not kept:  # this plane's points are no face: leave them to the capsules
            plane_ok[members] = False
    segs, seg_r, seg_n = [], [], []
    rest = np.flatnonzero(left)
    if len(rest):
        pairs = cKDTree(points[rest]).query_pairs(st.cell_m, output_type="ndarray")
        from scipy.sparse import coo_matrix
        graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(rest), len(rest)))
        _, comp = connected_components(graph, directed=False)
        for c in np.unique(comp):
            for a, b, r, m in _capsules(points[rest[comp == c]], st, rng):
                segs.append((a, b))
                seg_r.append(r)
                seg_n.append(m)
    return Envelope(tri=np.array(tris).reshape(-1, 3, 3), tri_radius=np.array(radii), tri_patch=np.array(tri_patch, int),
                    seg=np.array(segs).reshape(-1, 2, 3), seg_radius=np.array(seg_r),
                    patch_points=np.array(patch_points, int), seg_points=np.array(seg_n, int))


def _rectangle_distance(xy: np.ndarray, h: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Distances of points to a rectangle: their in-plane coordinates (n, 2), heights (n,) over its
    plane, and its corners (4, 2) in order."""
    o, u, v = corners[0], corners[1] - corners[0], corners[3] - corners[0]
    lu, lv = np.linalg.norm(u), np.linalg.norm(v)
    a, b = (xy - o) @ (u / lu), (xy - o) @ (v / lv)
    da, db = a - np.clip(a, 0, lu), b - np.clip(b, 0, lv)
    return np.sqrt(da * da + db * db + h * h)


def uncovered(points: np.ndarray, env: Envelope, tol: float = 1e-9) -> np.ndarray:
    """Indices of the points (P, 3) inside no volume of the envelope (empty when all are covered)."""
    return np.flatnonzero(depth(points, env) > tol)


def depth(points: np.ndarray, env: Envelope) -> np.ndarray:
    """min over the envelope's volumes of (distance to the core - radius) (P,) m: <= 0 inside one, and a
    ball of radius rho about the point is inside one when <= -rho."""
    P = len(points)
    margin = np.full(P, np.inf)  # min over volumes of (distance to core - radius)
    for k in range(len(env.tri)):
        v = np.broadcast_to(env.tri[k], (P, 3, 3))
        d = segment_triangle(points, points, v[:, 0], v[:, 1], v[:, 2]).distance - env.tri_radius[k]
        np.minimum(margin, d, out=margin)
    for k in range(len(env.seg)):
        s = np.broadcast_to(env.seg[k], (P, 2, 3))
        d = segment_segment(points, points, s[:, 0], s[:, 1]).distance - env.seg_radius[k]
        np.minimum(margin, d, out=margin)
    return margin


def radius_span(r: np.ndarray) -> str:
    """The range of radii r (n,) m for a log line, in mm ('12-40 mm'; '-' when there are none)."""
    return f"{1e3 * r.min():.0f}-{1e3 * r.max():.0f} mm" if len(r) else "-"
