"""Fold brackets of the voxel refinement (:mod:`capmap.capacity.refine`): per voxel, two points whose
IK branch counts differ (a fold of the IK map, a singular surface or the workspace boundary, lies
between them), bisected round by round, with each configuration's solution counts at both ends (the
configurations the fold ends are those whose counts differ)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FoldBrackets", "ConfigBrackets", "RoundPoints", "ConfigMidpoints"]


@dataclass(frozen=True)
class RoundPoints:
    """A round's evaluated points (N,): the voxel owning each, owner (N,) int; where, pts (N, 3) m; its IK
    branch count n_br (N,) int and its solutions per configuration cnt (N, C) int."""

    owner: np.ndarray
    pts: np.ndarray
    n_br: np.ndarray
    cnt: np.ndarray


@dataclass(frozen=True)
class ConfigMidpoints:
    """The evaluated midpoints of configuration brackets (n,): bracket (v, c), voxel v (n,) int and
    configuration c (n,) int; the midpoint pts (n, 3) m and configuration c's solution count there cnt (n,) int."""

    v: np.ndarray
    c: np.ndarray
    pts: np.ndarray
    cnt: np.ndarray


@dataclass
class FoldBrackets:
    """Fold brackets per voxel (V,): ``fold`` whether one is known, its ends fa, fb (V, 3) m, the branch
    count at fa (na) and each configuration's solution counts at both ends ca, cb (V, C); a first
    point of each voxel (ref_*) to compare later points with."""

    fold: np.ndarray
    fa: np.ndarray
    fb: np.ndarray
    na: np.ndarray
    ca: np.ndarray
    cb: np.ndarray
    ref_pt: np.ndarray
    ref_n: np.ndarray
    ref_c: np.ndarray

    @classmethod
    def empty(cls, V: int, C: int) -> "FoldBrackets":
        return cls(np.zeros(V, dtype=bool), np.zeros((V, 3)), np.zeros((V, 3)), np.zeros(V, dtype=int),
                   np.zeros((V, C), dtype=int), np.zeros((V, C), dtype=int), np.full((V, 3), np.nan), np.full(V, -1),
                   np.zeros((V, C), dtype=int))

    def track(self, points: RoundPoints, n_first_local: int, bisect: np.ndarray) -> None:
        """Update in place: a midpoint (the points ``n_first_local`` onwards of the local ones, one per
        voxel of ``bisect``) replaces the end whose branch count it shares; a voxel without a bracket
        gets one from any point whose count differs from its first point's."""
        owner, pts, n_br, cnt = points.owner, points.pts, points.n_br, points.cnt
        mids = np.arange(n_first_local, n_first_local + len(bisect))
        for i, v in zip(mids, bisect):
            if n_br[i] == self.na[v]:
                self.fa[v], self.ca[v] = pts[i], cnt[i]
            else:
                self.fb[v], self.cb[v] = pts[i], cnt[i]
        seen = self.ref_n >= 0
        vs, first = np.unique(owner, return_index=True)
        new = ~seen[vs]
        self.ref_pt[vs[new]] = pts[first[new]]
        self.ref_n[vs[new]] = n_br[first[new]]
        self.ref_c[vs[new]] = cnt[first[new]]
        differ = np.flatnonzero((n_br != self.ref_n[owner]) & ~self.fold[owner])
        if len(differ):
            v, i = np.unique(owner[differ], return_index=True)
            j = differ[i]
            self.fold[v] = True
            self.fa[v], self.na[v], self.ca[v] = self.ref_pt[v], self.ref_n[v], self.ref_c[v]
            self.fb[v], self.cb[v] = pts[j], cnt[j]


@dataclass
class ConfigBrackets:
    """Per voxel and configuration (V, C): two points whose solution counts of that configuration differ
    (the configuration's own boundary crosses the voxel: a singular surface where it meets another
    configuration, or a fold of the IK map), bisected round by round like :class:`FoldBrackets`. Its
    midpoints are ordinary points of the voxel: near a singular boundary the configuration's capacity
    falls to 0 (the joint rates grow without bound), and the bisection's last points find it.
    ``seen`` (V, C) a bracket exists (one per voxel and configuration); ends a, b (V, C, 3) m; count at a:
    na (V, C)."""

    seen: np.ndarray
    a: np.ndarray
    b: np.ndarray
    na: np.ndarray

    @classmethod
    def empty(cls, V: int, C: int) -> "ConfigBrackets":
        return cls(np.zeros((V, C), dtype=bool), np.zeros((V, C, 3)), np.zeros((V, C, 3)), np.zeros((V, C), dtype=int))

    def open(self, tol_m: float) -> np.ndarray:
        """(V, C) bool: a bracket longer than tol_m."""
        return self.seen & (np.linalg.norm(self.b - self.a, axis=2) > tol_m)

    def midpoints(self, tol_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The open brackets: voxel (n,), configuration (n,), midpoint (n, 3)."""
        v, c = np.nonzero(self.open(tol_m))
        return v, c, 0.5 * (self.a[v, c] + self.b[v, c])

    def track(self, mids: ConfigMidpoints, points: RoundPoints, ref_pt: np.ndarray, ref_c: np.ndarray) -> None:
        """Update in place: each evaluated midpoint of ``mids`` replaces its bracket's end whose count it
        shares; a (voxel, configuration) without a bracket so far gets one from the first of ``points``
        whose count differs from the voxel's first point's (ref_pt (V, 3) m, ref_c (V, C))."""
        v, c, mid_pts, mid_cnt = mids.v, mids.c, mids.pts, mids.cnt
        owner, pts, cnt = points.owner, points.pts, points.cnt
        same = mid_cnt == self.na[v, c]
        self.a[v[same], c[same]] = mid_pts[same]
        self.b[v[~same], c[~same]] = mid_pts[~same]
        i, c2 = np.nonzero((cnt != ref_c[owner]) & ~self.seen[owner])
        if len(i):
            _, first = np.unique(owner[i] * cnt.shape[1] + c2, return_index=True)
            i, c2 = i[first], c2[first]
            v2 = owner[i]
            self.seen[v2, c2] = True
            self.a[v2, c2], self.na[v2, c2], self.b[v2, c2] = ref_pt[v2], ref_c[v2, c2], pts[i]
