"""Limits on outputs that are affine in one scalar: ``|y0 + x s| <= L``.

The same shape of constraint appears throughout capmap, with different scalars x:

- capacity and verification: x = payload mass m (kg); y = joint torques and the base
  wrench of a fixed motion state, y(m) = y0 + m s;
- the torque-limited follower: x = path acceleration sdd (m/s^2) at a state (s, sd);
  tau = a sdd + (b sd^2 + c), i.e. y0 = b sd^2 + c and s = a.

Each output k alone admits the interval of x

    s_k > 0:  [(-L_k - y0_k) / s_k,  (L_k - y0_k) / s_k]
    s_k < 0:  [( L_k - y0_k) / s_k,  (-L_k - y0_k) / s_k]
    s_k = 0:  everything if |y0_k| <= L_k, nothing otherwise,

written once as ``lower = -(L + sign(s) y0) / |s|``, ``upper = (L - sign(s) y0) / |s|``.
The admissible set is the intersection over outputs. :class:`AffineLimits` holds the
limits L (n,) and the outputs' names; its methods batch on the leading axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.errors import CapmapError

__all__ = ["AffineLimits"]


@dataclass(frozen=True)
class AffineLimits:
    """|y_k| <= limit_k for n outputs named ``names`` (units in the names, e.g. ``tau_j2_nm``).

    limit: (n,) > 0, finite.
    """

    limit: np.ndarray
    names: tuple[str, ...]

    def __post_init__(self):
        limit = np.asarray(self.limit, dtype=float)
        if limit.shape != (len(self.names),):
            raise CapmapError(f"{len(self.names)} output names but limits of shape {limit.shape}")
        bad = np.flatnonzero(~(np.isfinite(limit) & (limit > 0)))
        if len(bad):
            raise CapmapError(f"limit {self.names[bad[0]]} = {limit[bad[0]]!r} must be finite and > 0")
        object.__setattr__(self, "limit", limit)
        object.__setattr__(self, "_limit_list", limit.tolist())  # for interval_one

    def __len__(self) -> int:
        return len(self.names)

    # ------------------------------------------------------------------ per output
    def upper_from_zero(self, y0: np.ndarray, s: np.ndarray, axis: int = -1) -> np.ndarray:
        """Per output, the largest x >= 0 keeping |y0 + x s| <= L for that output alone; 0 where the
        output already violates its limit at x = 0; inf where s = 0. y0, s: outputs along ``axis``."""
        limit = self._along(y0, axis)
        with np.errstate(divide="ignore", invalid="ignore"):
            bound = (limit - np.sign(s) * y0) / np.abs(s)
        bound[s == 0] = np.inf
        bound[np.abs(y0) > limit] = 0.0
        return np.maximum(bound, 0.0, out=bound)

    def bounds(self, y0: np.ndarray, s: np.ndarray, axis: int = -1) -> tuple[np.ndarray, np.ndarray]:
        """Per output, the interval [lower, upper] of admissible x (outputs along ``axis``);
        s = 0 gives (-inf, inf) if |y0| <= L, else the empty (inf, -inf)."""
        limit = self._along(y0, axis)
        with np.errstate(divide="ignore", invalid="ignore"):
            sign, mag = np.sign(s), np.abs(s)
            lower = -(limit + sign * y0) / mag
            upper = (limit - sign * y0) / mag
        flat = s == 0
        inside = np.abs(y0) <= limit
        lower = np.where(flat, np.where(inside, -np.inf, np.inf), lower)
        upper = np.where(flat, np.where(inside, np.inf, -np.inf), upper)
        return lower, upper

    # ------------------------------------------------------------------ over outputs
    def largest(self, y0: np.ndarray, s: np.ndarray, axis: int = -1) -> tuple[np.ndarray, np.ndarray]:
        """The largest x >= 0 with every |y0 + x s| <= L (0 when a limit is violated at x = 0; inf
        when unbounded) and the binding output's index; both with ``axis`` removed."""
        bound = self.upper_from_zero(y0, s, axis)
        binding = np.argmin(bound, axis=axis)
        return np.take_along_axis(bound, np.expand_dims(binding, axis), axis=axis).squeeze(axis), binding

    def interval(self, y0: np.ndarray, s: np.ndarray, axis: int = -1) -> tuple[np.ndarray, np.ndarray]:
        """[lo, hi] of x admissible for every output (``axis`` removed); lo > hi where none is."""
        lower, upper = self.bounds(y0, s, axis)
        return lower.max(axis=axis), upper.min(axis=axis)

    def interval_one(self, y0: list[float], s: list[float]) -> tuple[float, float]:
        """:meth:`interval` of one state, in plain Python floats (a control loop's hot path:
        no array overhead); the same formulas, so the same bits."""
        lo, hi = -np.inf, np.inf
        for yk, sk, lk in zip(y0, s, self._limit_list):
            if sk > 0:
                hi = min(hi, (lk - yk) / sk)
                lo = max(lo, -(lk + yk) / sk)
            elif sk < 0:
                hi = min(hi, (lk + yk) / -sk)
                lo = max(lo, -(lk - yk) / -sk)
            elif abs(yk) > lk:
                return np.inf, -np.inf
        return lo, hi

    def ratio(self, y: np.ndarray) -> np.ndarray:
        """|y| / L, outputs on the last axis."""
        return np.abs(y) / self.limit

    # ------------------------------------------------------------------ helpers
    def _along(self, y0: np.ndarray, axis: int) -> np.ndarray:
        shape = [1] * np.ndim(y0)
        shape[axis] = -1
        return self.limit.reshape(shape)
