"""Fold brackets of the voxel refinement (:mod:`capmap.capacity.refine`): per voxel, two points whose
IK branch counts differ (a fold of the IK map, a singular surface or the workspace boundary, lies
between them), bisected round by round, with each configuration's solution counts at both ends (the
configurations the fold ends are those whose counts differ)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FoldBrackets"]


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

    def track(self, owner, pts, n_br, cnt, n_first_local, bisect) -> None:
        """Update in place: a midpoint (the points ``n_first_local`` onwards of the local ones, one per
        voxel of ``bisect``) replaces the end whose branch count it shares; a voxel without a bracket
        gets one from any point whose count differs from its first point's. ``cnt`` (N, C) the points'
        solutions per configuration."""
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
