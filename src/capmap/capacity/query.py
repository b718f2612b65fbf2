"""Questions answered directly, without the pipeline: what can the arm carry at this point, on each of
its configurations, and along this straight line on one configuration.

:func:`point_query` solves every IK branch at the point (the task orientation), labels each by its
configuration (:mod:`capmap.core.configuration`) and gives each branch's exact capacity over the
run's motion directions (the capacity engine, one branch at a time: the worst direction, the binding
limit). :func:`line_query` starts on the configuration asked (default: the one of a reference
configuration, the arm's own), verifies the straight line as the verify stage verifies a path
(:func:`capmap.capacity.verification.verify_path` and :func:`~capmap.capacity.verification.judge`)
and returns its verdict.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.capacity.problem import CapacityProblem
from capmap.capacity.verification import PathResult, PathVerdict, judge, verify_path
from capmap.core.tracking import nearest_branch
from capmap.errors import CapmapError

__all__ = ["PointAnswer", "point_query", "LineAnswer", "line_query"]


@dataclass(frozen=True)
class PointAnswer:
    """Every IK branch at ``point_m`` (3,) m, K of them, sorted by configuration: configuration (K,)
    names, q_rad (K, n_active) joint angles, capacity_kg (K,), binding (K,) the limit that stops a
    heavier payload (``singular``: an exactly singular Jacobian), worst_u (K, 3) the motion direction
    of the minimum (unit vector, base frame)."""

    point_m: np.ndarray
    configuration: tuple[str, ...]
    q_rad: np.ndarray
    capacity_kg: np.ndarray
    binding: tuple[str, ...]
    worst_u: np.ndarray


def point_query(problem: CapacityProblem, point_m) -> PointAnswer:
    """The capacity of every IK branch at ``point_m`` (3,) m over the problem's directions (it must
    carry its configuration ``labels``).
    Raises :class:`CapmapError` (key ``point``) where no branch reaches it at the task orientation."""
    p = np.asarray(point_m, dtype=float).reshape(3)
    if not np.all(np.isfinite(p)):
        raise CapmapError(f"{{point}} = {p.tolist()} is not a finite position", point="the point")
    q, lab = _branches(problem, p)
    pc = problem.per_branch(q)
    order = np.lexsort((pc.capacity_kg, lab))
    return PointAnswer(point_m=p, configuration=tuple(problem.labels.names[i] for i in lab[order]), q_rad=q[order],
                       capacity_kg=pc.capacity_kg[order], binding=tuple(pc.names[b] for b in pc.binding[order]),
                       worst_u=pc.worst_u[order])


@dataclass(frozen=True)
class LineAnswer:
    """A straight line verified on one configuration: its name, the start configuration q_start_rad
    (n_active,), the verified path and its verdict carrying the payload."""

    configuration: str
    q_start_rad: np.ndarray
    result: PathResult
    verdict: PathVerdict


def line_query(problem: CapacityProblem, a_m, b_m, payload_kg: float, dt_s: float, configuration: str | None = None,
               q_reference: np.ndarray | None = None) -> LineAnswer:
    """Verify the straight line a_m -> b_m (3,) m carrying payload_kg, samples dt_s apart, starting on
    ``configuration`` (a name of ``problem.labels``; default: that of q_reference (n_active,) rad) at
    a_m: the branch of that configuration nearest q_reference (the first if none). Raises
    :class:`CapmapError` (keys ``configuration``, ``start``) for an unknown configuration or one that
    does not reach a_m."""
    names = problem.labels.names
    if configuration is None:
        if q_reference is None:
            raise CapmapError("{configuration}: give a configuration or a reference configuration",
                              configuration="the configuration")
        want = int(problem.labels.labels(np.asarray(q_reference, dtype=float)[None])[0])
    elif configuration in names:
        want = names.index(configuration)
    else:
        raise CapmapError(f"{{configuration}} {configuration!r} is not one of this arm's: {', '.join(names)}",
                          configuration="the configuration")
    a, b = (np.asarray(x, dtype=float).reshape(3) for x in (a_m, b_m))
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))) or np.allclose(a, b):
        raise CapmapError(f"{{start}}: the line [{', '.join(f'{v:g}' for v in a)}] -> "
                          f"[{', '.join(f'{v:g}' for v in b)}] m needs two distinct finite ends", start="the line")
    q, lab = _branches(problem, a)
    if not np.any(lab == want):
        raise CapmapError(f"{{configuration}} {names[want]} does not reach the line's start "
                          f"[{', '.join(f'{v:g}' for v in a)}] m (there: {', '.join(names[i] for i in np.unique(lab))})",
                          configuration="the configuration")
    q = q[lab == want]
    q0 = q[0 if q_reference is None else nearest_branch(q, np.asarray(q_reference, dtype=float))[0]]
    res = verify_path(problem.dyn, np.stack([a, b]), problem.rotation, q0, problem.motion, dt_s, problem.limits)
    _, verdict = judge(res, problem.arm, problem.limits, payload_kg)
    return LineAnswer(configuration=names[want], q_start_rad=q0, result=res, verdict=verdict)


def _branches(problem: CapacityProblem, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every IK branch at p (3,) m: q (K, n_active) rad and its configuration labels (K,); raises
    (key ``point``) where there is none."""
    arm = problem.arm
    sol = problem.branches(p[None])
    K = int(sol.n_solutions[0])
    if K == 0:
        raise CapmapError(f"{{point}} [{', '.join(f'{v:g}' for v in p)}] m is not reachable at the task orientation "
                          f"(no IK solution with joint {arm.locked_joint} locked)", point="the point")
    q = sol.q[0, :K]
    return q, problem.labels.labels(q)
