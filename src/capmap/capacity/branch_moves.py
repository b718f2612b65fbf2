"""Moves on one IK branch, for :mod:`capmap.capacity.branch_planning`: tracking a branch along
straight moves between voxel centres, the capacity of the tracked configurations along the
move's line, and the IK caches a search shares (none depends on the branch).

Tracking: at each sample the IK solution nearest the previous configuration (whole turns
allowed), by the verification's own :func:`capmap.core.tracking.follow_branches`; a move is executable when no joint
changes by more than ``max_step_rad`` between samples and every joint stays within its range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from capmap.capacity.engine import Motion, coefficients, motion_features
from capmap.capacity.planning import NEIGHBOURS
from capmap.capacity.voxels import Grid
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.core.limits import AffineLimits
from capmap.core.tracking import MAX_STEP_RAD, follow_branches, in_joint_range, nearest_branch

__all__ = ["TRACK_STEP_M", "BranchProblem", "fractions", "solve_at", "track_moves", "line_capacity", "move_capacity",
           "MoveCache"]

TRACK_STEP_M = 0.15  # m, the largest spacing of the tracked samples along a move (v_max * 1 s by default)


@dataclass(frozen=True)
class BranchProblem:
    """A search's fixed inputs: ``dyn`` (its ``arm`` is the locked arm), the voxel ``grid``,
    the task ``rotation`` (3, 3), ``motion`` and ``limits`` (on the arm's outputs); ``usable``
    (V,) bool, C-ordered over the grid: voxels that may be entered (a reachable point inside);
    ``step_m`` and ``max_step_rad`` of the tracking."""

    dyn: ArmDynamics
    grid: Grid
    rotation: np.ndarray
    motion: Motion
    limits: AffineLimits
    usable: np.ndarray
    step_m: float = TRACK_STEP_M
    max_step_rad: float = MAX_STEP_RAD


def fractions(length_m: float, step_m: float) -> np.ndarray:
    """Fractions 1/S .. 1 (S,) of a move of length_m sampled at most step_m apart."""
    S = max(1, math.ceil(length_m / step_m - 1e-9))
    return np.arange(1, S + 1) / S


def solve_at(problem: BranchProblem, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """IK sets (..., K, n) rad (NaN padded) and counts (...) at positions (..., 3)."""
    lead = pos.shape[:-1]
    sol = ik.solve(problem.dyn.arm, pos.reshape(-1, 3), problem.rotation)
    return sol.q.reshape(*lead, *sol.q.shape[1:]), sol.n_solutions.reshape(lead)


def track_moves(problem: BranchProblem, q0: np.ndarray, sets: np.ndarray,
                counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Track E moves from configurations q0 (E, n) rad through the IK sets (E, S, K, n) / counts
    (E, S) of their samples (in order; the last is the move's end), by
    :func:`capmap.core.tracking.follow_branches`.

    Returns ok (E,): every sample solved within ``max_step_rad`` of the previous configuration and
    within the joint ranges; and the tracked configurations (E, S, n) rad (NaN after a failure)."""
    arm = problem.dyn.arm
    path, failed_at, _ = follow_branches(sets, counts, q0, problem.max_step_rad)
    ok = (failed_at < 0) & np.all(in_joint_range(arm, path), axis=(1, 2))
    return ok, path


def line_capacity(dyn: ArmDynamics, q_active: np.ndarray, u: np.ndarray, motion: Motion,
                  limits: AffineLimits) -> np.ndarray:
    """Capacity (B,) kg of each configuration q_active (B, n_active) rad for straight-line motion
    along its own line u (B, 3) (unit vectors; either sense, v_max and a_max at once): the minimum
    of the two states u and -u, from the exact coefficients of :func:`capmap.capacity.engine.coefficients`.
    0 for an exactly singular configuration."""
    coef = coefficients(dyn, q_active)
    C = coef.stacked()  # (B, n_out, 10)
    cap = np.full(len(coef.c0), np.inf)
    for sense in (1.0, -1.0):
        w = sense * np.asarray(u, dtype=float)
        y0 = np.einsum("bok,bk->bo", C, motion_features(w, motion))  # each configuration its own direction
        s = np.einsum("boj,bj->bo", coef.S, motion.a_max_mps2 * w - dyn.gravity)
        cap = np.minimum(cap, limits.largest(y0, s)[0])
    cap[coef.singular] = 0.0
    return cap


def move_capacity(problem: BranchProblem, q0: np.ndarray, path: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Capacity (E,) kg of tracked moves: the smallest over the start q0 (E, n) and the samples
    path (E, S, n) rad for motion along each move's line u (E, 3) (unit)."""
    E, S, n = path.shape
    cfg = np.concatenate([q0[:, None, :], path], axis=1).reshape(-1, n)
    per = line_capacity(problem.dyn, cfg, np.repeat(u, S + 1, axis=0), problem.motion, problem.limits)
    return per.reshape(E, S + 1).min(axis=1) if E else np.zeros(0)


def _pad(sets: np.ndarray, K: int) -> np.ndarray:
    """IK sets (..., k, n) NaN-padded to K branches."""
    if sets.shape[-2] >= K:
        return sets
    pad = np.full(sets.shape[:-2] + (K - sets.shape[-2], sets.shape[-1]), np.nan)
    return np.concatenate([sets, pad], axis=-2)


@dataclass
class MoveCache:
    """Caches shared by the searches from several start branches (none depends on the branch):
    IK at voxel centres, and at the interior samples of every move between two neighbouring
    voxels (solved once for both senses)."""

    problem: BranchProblem
    centre: dict = field(default_factory=dict)  # flat voxel -> (IK set (K, n), count)
    edges: dict = field(default_factory=dict)  # (a, b), a < b -> (IK sets (S-1, K, n), counts (S-1,)) from a to b
    solved: set = field(default_factory=set)  # voxels whose moves are cached

    def __post_init__(self):
        g = self.problem.grid
        self.interior = fractions(g.edge_m * math.sqrt(3), self.problem.step_m)[:-1]  # (S-1,) one spacing for all

    def centre_of(self, v: int) -> np.ndarray:
        return self.problem.grid.centres(np.array(np.unravel_index(v, self.problem.grid.shape))[None])[0]

    def centre_set(self, v: int) -> np.ndarray:
        """The exact IK solutions (k, n) rad at voxel v's centre."""
        if v not in self.centre:
            sets, counts = solve_at(self.problem, self.centre_of(v)[None])
            self.centre[v] = (sets[0], int(counts[0]))
        q, c = self.centre[v]
        return q[:c]

    def state_at(self, v: int, q: np.ndarray) -> tuple[tuple, np.ndarray]:
        """The state a configuration q (n,) rad at voxel v's centre is: key (voxel, IK solution, whole
        turns per joint) and the exact solution with those turns (n,) rad."""
        sols = self.centre_set(v)
        k, q_c, _ = nearest_branch(sols, q)
        return (v, k, tuple(np.round((q_c - sols[k]) / (2 * np.pi)).astype(int))), q_c

    @staticmethod
    def _oriented(v: int, x: int, sets: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Interior-sample IK sets and counts of an edge, in the order from the lower voxel index to
        the higher, given in the order from v to x (and back: the same call turns them round)."""
        return (sets, counts) if v < x else (sets[::-1], counts[::-1])

    def voxel_moves(self, v: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Usable neighbours w (E,) of voxel v, their centres (E, 3) m, the IK sets (E, S, K, n) and
        counts (E, S) along each move v -> w (interior samples, then w's centre)."""
        g, pb = self.problem.grid, self.problem
        idx = np.array(np.unravel_index(v, g.shape))
        nb = idx + NEIGHBOURS
        nb = nb[np.all((nb >= 0) & (nb < np.array(g.shape)), axis=1)]
        nb = nb[pb.usable[g.flat(nb)]]
        w = g.flat(nb)
        if v not in self.solved:  # one IK batch: the missing edges' interior samples and the missing centres
            new = [int(x) for x in w if (min(v, x), max(v, x)) not in self.edges]
            cen = [int(x) for x in [v, *w] if x not in self.centre]
            p0 = self.centre_of(v)
            pts = [p0 + f * (self.centre_of(x) - p0) for x in new for f in self.interior] + [self.centre_of(x) for x in cen]
            if pts:
                sets, counts = solve_at(pb, np.array(pts))
                m = len(self.interior)
                for e, x in enumerate(new):
                    rows = slice(e * m, (e + 1) * m)
                    self.edges[(min(v, x), max(v, x))] = self._oriented(v, x, sets[rows], counts[rows])
                for c, x in enumerate(cen):
                    self.centre[x] = (sets[len(new) * m + c], int(counts[len(new) * m + c]))
            self.solved.add(v)
        S, n = len(self.interior) + 1, pb.dyn.arm.n_active
        if not len(w):
            return w, np.zeros((0, 3)), np.zeros((0, S, 1, n)), np.zeros((0, S), dtype=int)
        parts = [(*self._oriented(v, int(x), *self.edges[(min(v, int(x)), max(v, int(x)))]), *self.centre[int(x)])
                 for x in w]
        K = max([p[0].shape[1] for p in parts] + [p[2].shape[0] for p in parts], default=1)
        sets = np.array([np.concatenate([_pad(sl, K), _pad(cq, K)[None]]) for sl, cl, cq, cc in parts]).reshape(
            len(parts), S, K, n)
        counts = np.array([np.r_[cl, cc] for sl, cl, cq, cc in parts]).reshape(len(parts), S)
        return w, g.centres(nb), sets, counts
