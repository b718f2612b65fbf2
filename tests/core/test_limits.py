"""The affine-limit abstraction against brute force over a dense grid of the scalar."""

import numpy as np
import pytest

from capmap.core.limits import AffineLimits
from capmap.errors import CapmapError


def _limits(rng, n):
    return AffineLimits(rng.uniform(0.5, 2.0, n), tuple(f"y{k}" for k in range(n)))


@pytest.mark.parametrize("seed", range(20))
def test_interval_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    n = 6
    lim = _limits(rng, n)
    y0, s = 0.6 * rng.normal(size=n), rng.normal(size=n)
    s[rng.random(n) < 0.15] = 0.0
    lo, hi = lim.interval(y0, s)
    x = np.linspace(-60, 60, 240001)
    ok = np.all(np.abs(y0 + np.outer(x, s)) <= lim.limit, axis=1)
    if not ok.any():
        assert lo > hi or hi - lo < 1e-3
    else:
        assert lo == pytest.approx(max(x[ok].min(), -60), abs=1e-3) or lo < -60
        assert hi == pytest.approx(min(x[ok].max(), 60), abs=1e-3) or hi > 60
    # the plain-Python one-state version gives the same bits
    assert lim.interval_one(y0.tolist(), s.tolist()) == (lo, hi) or (lo > hi and np.subtract(*lim.interval_one(
        y0.tolist(), s.tolist())) > 0)


@pytest.mark.parametrize("seed", range(10))
def test_largest_from_zero_equals_brute_force(seed):
    rng = np.random.default_rng(100 + seed)
    n = 5
    lim = _limits(rng, n)
    y0, s = 0.8 * rng.normal(size=(50, n)), rng.normal(size=(50, n))
    cap, binding = lim.largest(y0, s)
    x = np.linspace(0, 30, 300001)
    for i in range(50):
        ok = np.all(np.abs(y0[i] + np.outer(x, s[i])) <= lim.limit, axis=1)
        if not ok[0]:
            assert cap[i] == 0  # violated with no payload: capacity 0 (the spec)
            assert abs(y0[i, binding[i]]) > lim.limit[binding[i]]
            continue
        first_bad = np.argmin(ok) if not ok.all() else len(x)
        expect = x[first_bad - 1] if first_bad < len(x) else np.inf
        assert cap[i] == pytest.approx(expect, abs=2e-4) or (cap[i] > 30 and np.isinf(expect))
        if np.isfinite(cap[i]):  # the binding output is at its limit there
            k = binding[i]
            assert abs(y0[i, k] + cap[i] * s[i, k]) == pytest.approx(lim.limit[k], rel=1e-12)


def test_violation_without_payload_gives_zero():
    lim = AffineLimits(np.array([700.0, 50.0]), ("a", "b"))
    y0 = np.array([[800.0, 0.0], [100.0, 0.0]])
    s = np.array([[-10.0, 1.0], [1.0, 1.0]])
    cap, b = lim.largest(y0, s)
    assert cap[0] == 0 and b[0] == 0  # |800| > 700 even though the payload would pull it back
    assert cap[1] == pytest.approx(50.0) and b[1] == 1  # second output binds: 0 + 50 * 1 = 50


def test_outputs_along_another_axis():
    rng = np.random.default_rng(7)
    lim = _limits(rng, 4)
    y0, s = rng.normal(size=(3, 4, 5)), rng.normal(size=(3, 4, 5))
    cap, b = lim.largest(y0, s, axis=1)
    cap_t, b_t = lim.largest(np.moveaxis(y0, 1, -1), np.moveaxis(s, 1, -1))
    assert np.array_equal(cap, cap_t) and np.array_equal(b, b_t)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf])
def test_limits_must_be_finite_and_positive(bad):
    with pytest.raises(CapmapError, match="limit y1"):
        AffineLimits(np.array([1.0, bad]), ("y0", "y1"))
