"""Inverse kinematics of a locked 6-joint arm: every branch, batched over target poses.

Closed form (complete, up to 8 branches) for chains of the shape

    joint 0 | joints 1, 2, 3 with parallel axes | joints 4, 5 with intersecting axes

(the SSRMS-type arm with joint 1, 2, 6 or 7 locked; UR-type arms), and for the same
shape reversed (solved on the inverse chain). It is derived from the chain's own fixed
transforms, so it does not assume any particular link lengths:

1. The point w where axes 4 and 5 meet is known from the target and is fixed in the
   link of joint 3. Its coordinate along the parallel-axis direction n is constant,
   and n depends on joint 0 only: ``A cos q0 + B sin q0 = C`` -> two q0.
2. n must map onto the target's frame through joints 4, 5 (a vector equation:
   Paden-Kahan subproblem 2) -> two q4, then q5.
3. The parallel group is a planar 3R with known end rotation and known point w:
   law of cosines -> two q2, then q1 and q3.

Semi-analytical (complete) for chains of the shape

    joint 0 | joint 1 | joints 2, 3 with parallel axes | joints 4, 5 with intersecting axes

(the SSRMS-type arm with joint 3, 4 or 5 locked: two parallel joints left), and reversed.
For a fixed q0 steps 1-3 above give joints 1, 4, 5 in closed form and leave the planar 2R group
one condition too many (Xu, She, Xu, Acta Astronautica 105, 2014, search q0 for it); it is
eliminated exactly, a resultant polynomial in q0 solved per pose, with the 1-D search around
roots known only approximately and on degenerate poses (:mod:`capmap.core.ik.semi.resultant`,
:mod:`capmap.core.ik.semi.search`).

Every solution is polished by Newton steps (two; up to eight for the semi-analytical and general
methods, whose roots can be ~1e-5 rad off), checked by forward kinematics
(position and orientation residual <= ``tol``), put inside the joint ranges and
de-duplicated. Every other chain of 6 revolute joints is solved by the general 6R method
(:mod:`capmap.core.ik.general.elimination`: Raghavan-Roth / Manocha-Canny elimination, up to 16 solutions,
complete; eight Newton steps polish its candidates). Only a chain it cannot take (not 6 joints)
uses a multi-start Newton solver (a deterministic Halton set of starts): found solutions are
exact, but completeness is not guaranteed (a warning, once per chain, says the map may overstate).

Each method is one :class:`IKMethod` (one call signature, a ``complete`` property):
:class:`ClosedForm` (:mod:`capmap.core.ik.closed`), :class:`SemiAnalytic` (:mod:`capmap.core.ik.semi.resultant`),
each also ``reversed``, :class:`GeneralSixR` (:mod:`capmap.core.ik.general.elimination`), :class:`MultiStartNewton`
(:mod:`capmap.core.ik.multistart`); :func:`solve` takes the first of :data:`METHODS` that applies.

The package:

One contract, :class:`~capmap.core.ik.registry.IKMethod`, and the registry that picks a method per chain
(:mod:`~capmap.core.ik.registry`: :func:`solve`, :func:`solve_chain`). One module or sub-package per method:

- :mod:`~capmap.core.ik.closed`      the closed form (joint 0 | three parallel | two intersecting axes)
- :mod:`~capmap.core.ik.semi`        the semi-analytical method (two parallel axes): the resultant
  polynomial (``resultant``), the 1-D search (``search``) and their compiled kernels (``kernels``)
- :mod:`~capmap.core.ik.general`     the general 6R elimination (Raghavan-Roth / Manocha-Canny): the
  elimination (``elimination``, ``matrices``, ``kernels``), the back-substitution (``back``) and the
  candidates' selection (``select``)
- :mod:`~capmap.core.ik.multistart`  the multi-start Newton fallback (not complete)

and what they share: :mod:`~capmap.core.ik.finish` (the common end of every method: Newton polish,
forward-kinematics check, joint ranges, de-duplication), :mod:`~capmap.core.ik.polish` (its compiled
Newton steps), :mod:`~capmap.core.ik.roots` (polynomial roots by companion matrices),
:mod:`~capmap.core.ik.classify` (a chain's axis geometry).
"""

from capmap.core.ik.registry import (
    COMPLETE_METHODS,
    METHODS,
    RESIDUAL_TOL,
    SEARCH_STEPS,
    ChainClass,
    ClosedForm,
    GeneralSixR,
    IKMethod,
    IKSolutions,
    MultiStartNewton,
    SemiAnalytic,
    classify,
    closed_form_shape,
    method_for,
    method_of,
    newton,
    semi_analytic_shape,
    solve,
    solve_chain,
    targets,
    wrap_to_range,
)

__all__ = ["IKSolutions", "IKMethod", "solve_chain", "GeneralSixR", "ClosedForm", "SemiAnalytic",
           "MultiStartNewton", "METHODS", "method_of", "solve", "newton", "wrap_to_range", "method_for",
           "closed_form_shape", "semi_analytic_shape", "COMPLETE_METHODS", "RESIDUAL_TOL", "SEARCH_STEPS",
           "ChainClass", "classify", "targets"]
