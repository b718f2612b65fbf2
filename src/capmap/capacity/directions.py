"""Sets of unit motion directions u for the straight-line motion set.

The paper parametrises u = [sin b cos a, sin b sin a, cos b] with a, b on a grid over
[0, 360) deg. That grid lists most directions twice (b and 360 - b with a + 180) and
the poles many times; :func:`paper_grid` keeps the first occurrence of each distinct
direction, which leaves every minimum over the set unchanged. :func:`sphere` gives a
near-uniform (Fibonacci) set of any size.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from capmap.capacity.sphere import start_directions
from capmap.errors import CapmapError

__all__ = ["Directions", "paper_grid", "sphere", "exact", "angles_deg", "antipodal_pairs", "GRID_AXES", "AXIS_LABELS",
           "grid_axes", "axis_of"]


@dataclass(frozen=True)
class Directions:
    """D unit directions: u (D, 3); alpha_deg, beta_deg (D,) their angles. ``exact``: the motion set is the
    whole sphere, u only the start of its exact minimum (:func:`exact`); a subset of it is not exact."""

    u: np.ndarray
    alpha_deg: np.ndarray
    beta_deg: np.ndarray
    kind: str
    exact: bool = False

    def __len__(self) -> int:
        return len(self.u)

    @cached_property
    def pairs(self) -> np.ndarray:
        """(P, 2): each direction once with the index of its antipode in the set (-1: none)."""
        return antipodal_pairs(self.u)


def antipodal_pairs(u: np.ndarray) -> np.ndarray:
    """(P, 2) int: each direction of u (D, 3) once, with the index of -u in the set (or -1)."""
    D = len(u)
    dots = u @ u.T
    partner = np.full(D, -1)
    for d in range(D):
        hit = np.flatnonzero(dots[d] < -1 + 1e-12)
        if len(hit):
            partner[d] = hit[0]
    rows, seen = [], np.zeros(D, dtype=bool)
    for d in range(D):
        if seen[d]:
            continue
        e = partner[d]
        seen[d] = True
        if e >= 0 and not seen[e]:
            seen[e] = True
            rows.append((d, e))
        else:
            rows.append((d, -1))
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def paper_grid(step_deg: float) -> Directions:
    """The paper's (a, b) grid over [0, 360) deg with step ``step_deg``, duplicates removed."""
    if not 0 < step_deg <= 180:
        raise CapmapError(f"step_deg = {step_deg!r} must be in (0, 180]")
    angles = np.arange(0.0, 360.0, step_deg)
    a, b = np.meshgrid(angles, angles, indexing="ij")
    a, b = a.ravel(), b.ravel()
    ar, br = np.deg2rad(a), np.deg2rad(b)
    u = np.stack([np.sin(br) * np.cos(ar), np.sin(br) * np.sin(ar), np.cos(br)], axis=1)
    _, first = np.unique(np.round(u, 9) + 0.0, axis=0, return_index=True)
    keep = np.sort(first)
    return Directions(u=u[keep], alpha_deg=a[keep], beta_deg=b[keep], kind=f"paper_grid({step_deg:g} deg)")


def sphere(n: int) -> Directions:
    """``n`` near-uniform directions on the unit sphere (Fibonacci lattice)."""
    if not isinstance(n, (int, np.integer)) or n < 1:
        raise CapmapError(f"n = {n!r} must be a positive integer")
    i = np.arange(n) + 0.5
    beta = np.arccos(1 - 2 * i / n)
    alpha = np.mod(np.pi * (1 + 5**0.5) * i, 2 * np.pi)
    u = np.stack([np.sin(beta) * np.cos(alpha), np.sin(beta) * np.sin(alpha), np.cos(beta)], axis=1)
    return Directions(u=u, alpha_deg=np.rad2deg(alpha), beta_deg=np.rad2deg(beta), kind=f"sphere({n})")


def angles_deg(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(alpha, beta) deg of unit directions u (..., 3): u = [sin b cos a, sin b sin a, cos b], a in [0, 360),
    b in [0, 180]."""
    beta = np.rad2deg(np.arccos(np.clip(u[..., 2], -1.0, 1.0)))
    return np.mod(np.rad2deg(np.arctan2(u[..., 1], u[..., 0])), 360.0), beta


def exact() -> Directions:
    """The whole sphere of directions: minima over it are exact (:mod:`capmap.capacity.sphere`); u is the
    start set of the minimisation (16 directions in antipodal pairs)."""
    u = start_directions()
    alpha, beta = angles_deg(u)
    return Directions(u=u, alpha_deg=alpha, beta_deg=beta, kind="exact", exact=True)


def _axes() -> np.ndarray:
    import itertools

    out = []
    for d in itertools.product((1, 0, -1), repeat=3):
        nz = [v for v in d if v]
        if nz and nz[0] > 0:  # one of d, -d: the first nonzero component positive
            out.append(d)
    return np.array(sorted(out, key=lambda d: (int(np.abs(d).sum()), [-v for v in d])), dtype=int)


GRID_AXES = _axes()
"""(13, 3) int: the move axes of the 26-neighbour voxel grid, each once (d and -d share an axis):
x, y, z, then the 6 face diagonals, then the 4 space diagonals."""

AXIS_LABELS = tuple("".join(("-" if v < 0 else "+") + "xyz"[c] for c, v in enumerate(d) if v).lstrip("+")
                    for d in GRID_AXES)
"""Labels of :data:`GRID_AXES`: 'x', 'y', 'z', 'x+y', 'x-y', ..., 'x-y-z'."""


def grid_axes() -> Directions:
    """The 26 unit directions of the voxel grid's moves: the 13 axes, then their opposites (so
    :attr:`Directions.pairs` is [[a, a + 13]] for axis a)."""
    d = np.concatenate([GRID_AXES, -GRID_AXES]).astype(float)
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    alpha, beta = angles_deg(u)
    return Directions(u=u, alpha_deg=alpha, beta_deg=beta, kind="grid_axes(13)")


def axis_of(offsets: np.ndarray) -> np.ndarray:
    """Index into :data:`GRID_AXES` of neighbour offsets (..., 3) int (d and -d give the same axis)."""
    offsets = np.asarray(offsets, dtype=int)
    eq = np.all(offsets[..., None, :] == GRID_AXES, axis=-1) | np.all(offsets[..., None, :] == -GRID_AXES, axis=-1)
    if not np.all(eq.any(axis=-1)):
        raise CapmapError("offsets must be nonzero vectors of -1, 0, 1")
    return np.argmax(eq, axis=-1)
