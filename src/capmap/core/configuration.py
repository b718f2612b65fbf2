"""Configuration labels of IK solutions: the branch name that is constant between singular surfaces,
as industrial controllers name it, so that a map per configuration is the map of the arm the operator
has in front of them.

A label is a tuple of signs of functions of the joint angles alone, each vanishing only on singular
configurations (det J = 0), so a motion that crosses no singular surface never changes its label.

- :class:`ShoulderElbowWrist`, chains with a closed form (``0 | 1 2 3 parallel | 4 5 intersecting``,
  on the chain or from its tip; the SSRMS with joint 1, 2, 6 or 7 locked, UR-type arms): the three
  branch choices of the closed form (:func:`capmap.core.ik.closed.flags`), shoulder, elbow and wrist.
  det J is their product times a constant (measured 0.5 on the SSRMS: tests/core/test_configuration.py),
  so every singular surface is where exactly one flag changes sign: 8 configurations, at most one IK
  solution each.
- :class:`Aspects`, every other chain (the semi-analytical and general 6R ones): the sign of det J,
  its two aspects. Their det J has no known factors, so this is the finest label that is constant
  between singular surfaces from the joint angles alone; an aspect can hold several IK solutions
  (the arm can move between them without crossing a singularity), and a map per aspect is the
  minimum over them.

A configuration exactly on a singular surface (a flag exactly 0) takes the + side; such points
have measure zero and capacity 0 on both sides.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

import capmap.core.ik.closed as ik_closed
from capmap.core import ik
from capmap.core.kinematics import Chain

__all__ = ["Configurations", "ShoulderElbowWrist", "Aspects", "configurations_of", "arm_configurations"]


class Configurations(ABC):
    """Configuration labels of one chain: ``labels(theta (M, 6) rad) -> (M,) int`` in
    [0, len(names)), ``names`` (C,) str, ``flags(theta) -> (M, F)`` the signed functions whose signs
    make the label, ``description``: what the flags are, for reports."""

    names: tuple[str, ...]

    @abstractmethod
    def flags(self, theta: np.ndarray) -> np.ndarray:
        ...

    @property
    @abstractmethod
    def description(self) -> str:
        ...

    def labels(self, theta: np.ndarray) -> np.ndarray:
        f = self.flags(np.atleast_2d(np.asarray(theta, dtype=float)))
        bits = (f >= 0).astype(np.int64)  # on a singular surface (flag exactly 0): the + side
        return (bits * (1 << np.arange(f.shape[1] - 1, -1, -1))).sum(axis=1)


def _sign_names(letters: str) -> tuple[str, ...]:
    n = len(letters)
    return tuple("".join(f"{c}{'+' if (k >> (n - 1 - i)) & 1 else '-'}" for i, c in enumerate(letters))
                 for k in range(1 << n))


@dataclass(frozen=True)
class ShoulderElbowWrist(Configurations):
    """Shoulder, elbow and wrist flags of a closed-form chain (``reversed``: of its inverse chain, the
    shape seen from the tip); names ``S+E-W+`` etc., the flags' signs in that order (label 4 s + 2 e + w,
    a flag's bit 1 for +). ``joints`` (6,): the arm's 1-based numbers of the chain's joints, for the
    description."""

    chain: Chain
    reversed: bool = False
    joints: tuple[int, ...] = (1, 2, 3, 4, 5, 6)
    names: tuple[str, ...] = _sign_names("SEW")

    def flags(self, theta: np.ndarray) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        if not self.reversed:
            return ik_closed.flags(self.chain, theta)
        f = ik_closed.flags(self.chain.reversed(), -theta[..., ::-1])
        return f[:, ::-1]  # from the base: the tip chain's joint 4 is the shoulder, its joint 0 the wrist

    @property
    def description(self) -> str:
        j = self.joints[::-1] if self.reversed else self.joints
        s, e, w = (j[4], j[2], j[0]) if self.reversed else (j[0], j[2], j[4])
        return (f"S: shoulder (joint {s}'s branch), E: elbow (joint {e}), W: wrist (joint {w}); each the sign of "
                "d/dq of that joint's closed-form equation, 0 on a singular surface; det J is their product")


@dataclass(frozen=True)
class Aspects(Configurations):
    """The sign of det J (the geometric Jacobian of the chain, (6, 6)): names ``A+``, ``A-``... in
    label order (label 1: det J >= 0)."""

    chain: Chain
    names: tuple[str, ...] = ("A-", "A+")

    def flags(self, theta: np.ndarray) -> np.ndarray:
        _, J = self.chain.jacobian(np.asarray(theta, dtype=float))
        return np.linalg.det(J)[:, None]

    @property
    def description(self) -> str:
        return ("A: the aspect, the sign of det J (no finer label is constant between singular surfaces on this "
                "chain; an aspect can hold several IK solutions)")


def configurations_of(chain: Chain, method: str, joints: tuple[int, ...] | None = None) -> Configurations:
    """The labels for a chain solved by IK ``method`` (:func:`capmap.core.ik.method_for`)."""
    joints = tuple(joints) if joints is not None else tuple(range(1, chain.n + 1))
    if method in ("closed_form", "closed_form_reversed"):
        return ShoulderElbowWrist(chain, reversed=method.endswith("_reversed"), joints=joints)
    return Aspects(chain)


def arm_configurations(arm) -> Configurations:
    """The labels of a locked arm's chain (:class:`capmap.core.reduction.LockedArm`), by the IK method
    that solves it; a label's joints are the arm's own numbers."""
    return configurations_of(arm.chain, ik.method_for(arm.chain), arm.active_joint_numbers)
