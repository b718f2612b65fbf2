"""The IK contract (:class:`IKMethod`: one call signature, a ``complete`` property) and the registry:
:func:`solve` takes the first of :data:`METHODS` that applies to the locked arm's chain. The methods,
their shapes and what each guarantees are described in :mod:`capmap.core.ik`."""

from __future__ import annotations

import logging
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

import capmap.core.ik.classify as ik_classify
import capmap.core.ik.closed as ik_closed
import capmap.core.ik.general.select as ik_general_select
import capmap.core.ik.semi.resultant as ik_semi_poly
import capmap.core.ik.semi.search as ik_semi
from capmap.core.ik.classify import ChainClass
from capmap.core.ik.finish import RESIDUAL_TOL, IKSolutions, _finish, wrap_to_range
from capmap.core.ik.multistart import multi_start, newton
from capmap.core.kinematics import Chain, inverse_transform
from capmap.core.reduction import LockedArm

__all__ = ["IKSolutions", "IKMethod", "solve_chain",
           "GeneralSixR", "ClosedForm", "SemiAnalytic", "MultiStartNewton", "METHODS", "method_of", "solve",
           "newton", "wrap_to_range", "method_for", "closed_form_shape", "semi_analytic_shape", "COMPLETE_METHODS",
           "RESIDUAL_TOL", "SEARCH_STEPS", "ChainClass", "classify", "targets"]

log = logging.getLogger(__name__)

_GEOM_TOL = 1e-9
SEARCH_STEPS = ik_semi.SEARCH_STEPS


# --------------------------------------------------------------------------- structure


def _parallel(X: np.ndarray) -> bool:
    """Axis of the next joint parallel to the current one (rotation maps e_z to +-e_z)."""
    return abs(X[2, 2]) > 1 - _GEOM_TOL


def _intersecting(X: np.ndarray) -> bool:
    p, d = X[:3, 3], X[:3, 2]
    if _parallel(X):
        return False
    cross = np.cross([0.0, 0.0, 1.0], d)
    return abs(p @ cross) / np.linalg.norm(cross) < _GEOM_TOL


def closed_form_shape(chain: Chain) -> bool:
    """True when the chain is ``0 | 1 2 3 parallel | 4 5 intersecting``."""
    X = chain.X
    return (chain.n == 6 and not _parallel(X[1]) and _parallel(X[2]) and _parallel(X[3])
            and not _parallel(X[4]) and _intersecting(X[5]))


def semi_analytic_shape(chain: Chain) -> bool:
    """True when the chain is ``0 | 1 | 2 3 parallel | 4 5 intersecting`` (joint 0 searched)."""
    X = chain.X
    return (chain.n == 6 and not _parallel(X[2]) and _parallel(X[3]) and np.hypot(*X[3][:2, 3]) > _GEOM_TOL
            and not _parallel(X[4]) and _intersecting(X[5]))


# --------------------------------------------------------------------------- driver

_WARNED: set[bytes] = set()


def _warn_incomplete(chain: Chain) -> None:
    key = chain.X.tobytes()
    if key not in _WARNED:
        _WARNED.add(key)
        log.warning("IK: this chain (%d joints) has no complete solver (those need 6 revolute joints); multi-start "
                    "Newton finds exact solutions but may miss branches, so the capacity map may overstate",
                    chain.n)


# --------------------------------------------------------------------------- methods


def targets(positions: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Target poses (N, 4, 4) from positions (N, 3) m and a rotation (3, 3) or (N, 3, 3)."""
    positions = np.atleast_2d(np.asarray(positions, dtype=float))
    N = len(positions)
    T = np.zeros((N, 4, 4))
    T[:, :3, :3] = rotation
    T[:, :3, 3] = positions
    T[:, 3, 3] = 1.0
    return T


class IKMethod(ABC):
    """An inverse-kinematics method: the contract of every solver, one subclass per method.

    ``solve(arm, positions, rotation, tol)``: for N target poses (positions (N, 3) m, rotation
    (3, 3) or (N, 3, 3) in the base frame) the :class:`IKSolutions` q (N, K, n_active) rad, NaN
    beyond n_solutions (N,) in each row. Every returned solution is exact (position and orientation
    residual <= tol by the chain's FK), inside the joint ranges and distinct from the others of its
    row. ``complete``: every branch is found (a complete method's set is all solutions); an
    incomplete one returns a subset. ``applies(chain)``: the chain has the shape the method solves.

    A subclass gives its raw ``candidates``; :meth:`solve` polishes (two Newton steps), checks,
    wraps into the ranges and de-duplicates them, the same for every method.
    """

    @property
    @abstractmethod
    def name(self) -> str:
        """The method's name, as :attr:`IKSolutions.method` and :func:`method_for` give it."""

    @property
    @abstractmethod
    def complete(self) -> bool:
        """True when the method finds every IK branch."""

    polish: int = 2  # Newton steps on every candidate not already at rounding level

    @abstractmethod
    def applies(self, chain: Chain) -> bool:
        """Whether the method solves this chain (its shape)."""

    @abstractmethod
    def candidates(self, chain: Chain, T: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Raw candidate solutions (N, K, n) rad and their validity (N, K) for targets T (N, 4, 4)
        (lower, upper (n,) rad: the joint ranges, which only a search method uses)."""

    def solve(self, arm: LockedArm, positions: np.ndarray, rotation: np.ndarray, tol: float = RESIDUAL_TOL) -> IKSolutions:
        """Every solution this method finds for each target (see the class docstring); ValueError when
        the method does not apply to ``arm``'s chain."""
        if not self.applies(arm.chain):
            raise ValueError(f"IK method {self.name} does not apply to the chain of {arm.robot.name}")
        return self.solve_chain(arm.chain, targets(positions, rotation), arm.q_lower, arm.q_upper, tol)

    def solve_chain(self, chain: Chain, T: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                    tol: float = RESIDUAL_TOL) -> IKSolutions:
        """As :meth:`solve` for a bare chain: targets T (N, 4, 4), joint ranges lower, upper (n,) rad."""
        theta, ok = self.candidates(chain, T, lower, upper)
        return _finish(chain, theta, ok, T, lower, upper, tol, self.name, self.polish)


class _ShapeMethod(IKMethod):
    """A complete method for one chain shape, solved on the chain or, ``reversed``, from its tip (on
    the inverse chain, the angles mapped back): subclasses give ``_label``, ``_shape`` and ``_raw``."""

    reversed: bool = False
    _label: str
    _shape: staticmethod
    _raw: staticmethod

    @property
    def name(self) -> str:
        return f"{self._label}_reversed" if self.reversed else self._label

    @property
    def complete(self) -> bool:
        return True

    def applies(self, chain: Chain) -> bool:
        return chain.n == 6 and self._shape(chain.reversed()) if self.reversed else self._shape(chain)

    def candidates(self, chain: Chain, T: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if not self.reversed:
            return self._raw(chain, T)
        theta_r, ok = self._raw(chain.reversed(), inverse_transform(T))
        return -theta_r[..., ::-1], ok


@dataclass(frozen=True)
class ClosedForm(_ShapeMethod):
    """Closed form (complete, up to 8 branches; :mod:`capmap.core.ik.closed`) for chains
    ``0 | 1 2 3 parallel | 4 5 intersecting``; ``reversed``: that shape from the tip, solved on the
    inverse chain."""

    reversed: bool = False
    _label = "closed_form"
    _shape = staticmethod(closed_form_shape)
    _raw = staticmethod(ik_closed.branches)


_SEMI: dict[bytes, ik_semi_poly.SemiPolynomial] = {}


def _semi_candidates(chain: Chain, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    key = chain.X.tobytes()
    if key not in _SEMI:
        _SEMI[key] = ik_semi_poly.prepare(chain, reversible=semi_analytic_shape(chain.reversed()))
    return ik_semi_poly.candidates(_SEMI[key], T)


@dataclass(frozen=True)
class SemiAnalytic(_ShapeMethod):
    """The semi-analytical method (complete) for chains ``0 | 1 | 2 3 parallel | 4 5 intersecting``:
    the real roots in joint 0 of one resultant polynomial (:mod:`capmap.core.ik.semi.resultant`), the
    1-D search (:mod:`capmap.core.ik.semi.search`) around roots known only approximately and on degenerate
    poses; ``reversed``: that shape from the tip."""

    reversed: bool = False
    polish: int = 8  # roots of clustered solutions beside a fold are known to ~1e-5 rad: Newton converges from there
    _label = "semi_analytic"
    _shape = staticmethod(semi_analytic_shape)
    _raw = staticmethod(_semi_candidates)


_GENERAL: dict[bytes, "ik_general_select.GeneralSolver"] = {}


def _general_solver(chain: Chain) -> "ik_general_select.GeneralSolver":
    key = chain.X.tobytes()
    if key not in _GENERAL:
        _GENERAL[key] = ik_general_select.prepare(chain)
    return _GENERAL[key]


@dataclass(frozen=True)
class GeneralSixR(IKMethod):
    """Every solution of any 6-joint revolute chain (:mod:`capmap.core.ik.general.elimination`: Raghavan-Roth /
    Manocha-Canny elimination, a companion eigenproblem per pose). Poses it cannot vouch for (every
    formulation degenerate, a solution lost, four axes nearly parallel: ik_general_select) go to the
    semi-analytical method where the chain has its shape (complete), else to the multi-start search,
    with a warning that branches may be missing there."""

    polish: int = 8  # the eliminated roots of clustered solutions can be 1e-2 rad off: Newton converges from there

    @property
    def name(self) -> str:
        return "general_6r"

    @property
    def complete(self) -> bool:
        return True

    def applies(self, chain: Chain) -> bool:
        return chain.n == 6

    def candidates(self, chain: Chain, T: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        theta, ok, degenerate = ik_general_select.candidates(_general_solver(chain), np.ascontiguousarray(T))
        if not degenerate.any():
            return theta, ok
        search = next((m for m in (SemiAnalytic(), SemiAnalytic(reversed=True)) if m.applies(chain)), None)
        if search is not None:  # a complete method for this chain shape takes the poses no elimination solved
            extra, extra_ok = search.candidates(chain, T[degenerate], lower, upper)
        else:
            log.warning("IK: %d of %d poses are degenerate for the exact 6R method (a continuum of solutions, "
                        "four nearly parallel axes, a lost root); multi-start Newton is used there and may miss "
                        "branches (the map may overstate there)", int(degenerate.sum()), len(T))
            extra, extra_ok = multi_start(chain, T[degenerate], lower, upper)
        pad = np.zeros((len(T), extra.shape[1], chain.n))
        pad_ok = np.zeros((len(T), extra.shape[1]), dtype=bool)
        pad[degenerate], pad_ok[degenerate] = extra, extra_ok
        return np.concatenate([theta, pad], axis=1), np.concatenate([ok, pad_ok], axis=1)


@dataclass(frozen=True)
class MultiStartNewton(IKMethod):
    """Multi-start damped Newton from a deterministic Halton set of starts (:func:`capmap.core.ik.multistart.multi_start`):
    any chain, exact solutions, but NOT complete (branches may be missed)."""

    @property
    def name(self) -> str:
        return "numeric"

    @property
    def complete(self) -> bool:
        return False

    def applies(self, chain: Chain) -> bool:
        return True

    def candidates(self, chain: Chain, T: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return multi_start(chain, T, lower, upper)


METHODS: tuple[IKMethod, ...] = (ClosedForm(), ClosedForm(reversed=True), SemiAnalytic(), SemiAnalytic(reversed=True),
                                 GeneralSixR(), MultiStartNewton())  # in the order :func:`solve` tries them
# Semi-analytical before general 6R on the SSRMS middle locks: on 30,000 seeded poses it missed none of the 202,470
# solutions the 1-D search and the general method found (they missed 4 and 22), and it is faster (README).
COMPLETE_METHODS = tuple(m.name for m in METHODS if m.complete)


def method_of(chain: Chain) -> IKMethod:
    """The method :func:`solve` uses for this chain: the first of :data:`METHODS` that applies."""
    return next(m for m in METHODS if m.applies(chain))


def method_for(chain: Chain) -> str:
    """The name of the method :func:`solve` uses for this chain."""
    return method_of(chain).name


def solve(arm: LockedArm, positions: np.ndarray, rotation: np.ndarray, tol: float = RESIDUAL_TOL) -> IKSolutions:
    """Every distinct IK solution of the locked arm for each target position, by :func:`method_of`
    the arm's chain (a warning once per chain when that method is not complete).

    positions: (N, 3) m. rotation: (3, 3) or (N, 3, 3), end-effector orientation in the
    base frame. Returns active-joint angles within the joint ranges, residual <= tol.
    """
    return solve_chain(arm.chain, targets(positions, rotation), arm.q_lower, arm.q_upper, tol)


def solve_chain(chain: Chain, T: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                tol: float = RESIDUAL_TOL) -> IKSolutions:
    """As :func:`solve` for a bare chain: targets T (N, 4, 4) in the chain's base frame, joint
    ranges lower, upper (n,) rad."""
    method = method_of(chain)
    if not method.complete:
        _warn_incomplete(chain)
    return method.solve_chain(chain, np.asarray(T, dtype=float), lower, upper, tol)


def classify(chain: Chain) -> ChainClass:
    """The chain's axis geometry and the IK method :func:`solve` uses for it (:mod:`capmap.core.ik.classify`)."""
    method = method_of(chain)
    return ik_classify.classify(chain, method.name, method.complete)
