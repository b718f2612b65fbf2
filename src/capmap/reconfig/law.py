"""The motion law of the unlocked passive joint: theta and d move rest to rest on a quintic."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.errors import CapmapError

__all__ = ["quintic", "QuinticLaw"]


def quintic(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """s = 10 u^3 - 15 u^4 + 6 u^5 and its first two derivatives by u, for u in [0, 1] (clipped):
    0 -> 1 with zero velocity and acceleration at both ends; peak s' = 1.875 at u = 1/2."""
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    return u**3 * (10 - 15 * u + 6 * u**2), 30 * u**2 * (1 - u) ** 2, 60 * u * (1 - u) * (1 - 2 * u)


@dataclass(frozen=True)
class QuinticLaw:
    """theta: theta0 -> theta1 rad, d: d0 -> d1 m, both on quintic(t / duration_s)."""

    theta0: float
    theta1: float
    d0: float
    d1: float
    duration_s: float

    def __post_init__(self):
        if not (np.isfinite(self.duration_s) and self.duration_s > 0):
            raise CapmapError(f"duration_s = {self.duration_s!r} must be finite and > 0")

    def at(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(theta rad, d m, dtheta/du, dd/du) at law phases u (fraction of the law, 0..1)."""
        s, ds, _ = quintic(u)
        dth, dd = self.theta1 - self.theta0, self.d1 - self.d0
        return self.theta0 + dth * s, self.d0 + dd * s, dth * ds, dd * ds

    def speed_weight(self, u: np.ndarray) -> np.ndarray:
        """The law's speed relative to its peak, 0 at rest (both ends), 1 at mid-motion."""
        return quintic(u)[1] / 1.875
