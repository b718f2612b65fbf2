"""Settings of the dual-arm optimiser (plain data, no solver imported): cost weights, the
augmented-Lagrangian loop's parameters, a solve's options and an iterative method's stop rule."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["Weights", "ALSettings", "SolveOptions", "StopRule"]


@dataclass(frozen=True)
class Weights:
    """Cost weights: control (nq,) on u, velocity, panel error; collision margin m."""

    control: np.ndarray
    velocity: float
    panel: float
    margin_m: float


@dataclass(frozen=True)
class ALSettings:
    """mu0, mu_factor, decrease (the violation must drop this many times per outer iteration or mu
    grows), mu_max; outer and inner iteration limits; FDDP's stop threshold; the tolerance on
    the violation (m or rad); filter_m: the collision pairs kept per node."""

    mu0: float = 100.0
    mu_factor: float = 10.0
    decrease: float = 4.0
    mu_max: float = 1e9
    max_outer: int = 30
    max_inner: int = 30
    inner_stop: float = 1e-9
    tolerance: float = 1e-7
    filter_m: float = 0.1


@dataclass(frozen=True)
class SolveOptions:
    """How a solve runs (not what it solves): ``log`` (a line's sink, None: silent); ``inequalities=False``: the
    equality-only problem (no collision pairs, no limits); ``compiled=False``: Pinocchio's node models and
    Crocoddyl's FDDP (the reference) instead of the compiled ones."""

    log: Callable[[str], None] | None = None
    inequalities: bool = True
    compiled: bool = True


@dataclass(frozen=True)
class StopRule:
    """An iterative method's stop: at most ``iterations`` iterations, or once its residual (the method's own
    measure: a pose error norm in m and rad, a KKT residual) is below ``tolerance``."""

    iterations: int
    tolerance: float
