"""Settings of the dual-arm optimiser (plain data, no solver imported): cost weights and the
augmented-Lagrangian loop's parameters."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Weights", "ALSettings"]


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
