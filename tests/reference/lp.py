"""The largest admissible payload as a linear programme (scipy HiGHS), the reference for the
closed-form capacity."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog


def lp_capacity(y0: np.ndarray, s: np.ndarray, limit: np.ndarray) -> float:
    """max m s.t. -L <= y0 + m s <= L, m >= 0; 0 if infeasible at m = 0, inf if unbounded."""
    if np.any(np.abs(y0) > limit):
        return 0.0
    res = linprog(c=[-1.0], A_ub=np.concatenate([s, -s])[:, None], b_ub=np.concatenate([limit - y0, limit + y0]),
                  bounds=[(0, None)], method="highs")
    return np.inf if res.status == 3 else res.x[0]
