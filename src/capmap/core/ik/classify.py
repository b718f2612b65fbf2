"""The geometry of a chain's joint axes, for users and for the choice of IK method: which
consecutive axes are parallel, intersecting, collinear or skew, which triples meet in a point
(Pieper's spherical wrist or shoulder). :func:`capmap.core.ik.classify` adds the method."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.core.kinematics import Chain

__all__ = ["ChainClass", "classify"]

_CLASS_TOL = 1e-9  # m and rad: axes closer than this to parallel / intersecting / collinear count as such


@dataclass(frozen=True)
class ChainClass:
    """The geometry of a chain's joint axes, as :func:`classify` finds it (joints counted from 1 in
    the chain, i.e. among the active joints).

    pairs: for each consecutive pair (i, i+1) one of ``parallel``, ``intersecting``, ``collinear``,
    ``skew``. spherical: triples of consecutive joints whose axes meet in one point (Pieper's
    wrist or shoulder). collinear: consecutive joints whose axes are one line (a locked joint
    between them held them there; a continuum of solutions: the two joints move as one).
    method: the IK method :func:`solve` uses; complete: it finds every branch."""

    n: int
    pairs: tuple[str, ...]
    spherical: tuple[tuple[int, int, int], ...]
    collinear: tuple[tuple[int, int], ...]
    method: str
    complete: bool

    def describe(self) -> str:
        """One line: the axis relations, spherical groups, collinear pairs and the method."""
        rel = ", ".join(f"{i + 1}-{i + 2} {p}" for i, p in enumerate(self.pairs))
        sph = "; ".join(" ".join(map(str, t)) for t in self.spherical) or "none"
        col = "; ".join(f"{a}={b}" for a, b in self.collinear)
        text = f"{self.n} joints: {rel}; axes meeting in a point: {sph}"
        if col:
            text += f"; COLLINEAR axes {col} (a continuum of solutions: the map may overstate)"
        return text + f" -> IK {self.method} ({'complete' if self.complete else 'may miss branches'})"


def _axes(chain: Chain) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) and unit directions (n, 3) of the joint axes at zero angles, base frame."""
    points, dirs = [], []
    T = chain.X[0]
    for k in range(chain.n):
        points.append(T[:3, 3].copy())
        dirs.append(T[:3, 2].copy())
        T = T @ chain.X[k + 1]
    return np.array(points), np.array(dirs)


def _line_distance(p1, d1, p2, d2) -> tuple[float, float]:
    """(sin of the angle between two lines, their distance) m."""
    c = np.cross(d1, d2)
    s = float(np.linalg.norm(c))
    if s < _CLASS_TOL:
        return s, float(np.linalg.norm(np.cross(p2 - p1, d1)))
    return s, float(abs((p2 - p1) @ c) / s)


def classify(chain: Chain, method: str, complete: bool) -> ChainClass:
    """The chain's axis geometry (tolerance 1e-9 m and rad), with the name of its IK method and
    whether that method is complete; see :class:`ChainClass`.
    Relations of consecutive axes do not depend on the joint angles."""
    P, D = _axes(chain)
    pairs = []
    for i in range(chain.n - 1):
        s, dist = _line_distance(P[i], D[i], P[i + 1], D[i + 1])
        pairs.append("collinear" if s < _CLASS_TOL and dist < _CLASS_TOL else "parallel" if s < _CLASS_TOL
                     else "intersecting" if dist < _CLASS_TOL else "skew")
    spherical = []
    for i in range(chain.n - 2):
        A = np.stack([np.eye(3) - np.outer(d, d) for d in D[i:i + 3]])
        b = np.einsum("kij,kj->ki", A, P[i:i + 3])
        x, *_ = np.linalg.lstsq(A.reshape(9, 3), b.reshape(9), rcond=None)
        far = max(float(np.linalg.norm(np.cross(x - P[k], D[k]))) for k in range(i, i + 3))
        if far < _CLASS_TOL * 10 and all(pairs[k] == "intersecting" for k in (i, i + 1)):
            spherical.append((i + 1, i + 2, i + 3))
    collinear = [(i + 1, i + 2) for i, p in enumerate(pairs) if p == "collinear"]
    return ChainClass(n=chain.n, pairs=tuple(pairs), spherical=tuple(spherical), collinear=tuple(collinear),
                      method=method, complete=complete and not collinear)
