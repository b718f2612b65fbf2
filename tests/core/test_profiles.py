"""Trapezoidal rest-to-rest timing: known answers and properties checked by numerical integration."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.core.profiles import sample_segments, scurve, trapezoid
from capmap.errors import CapmapError


@pytest.mark.parametrize("L, duration", [
    (4.772639843943811, 4.772639843943811 / 0.15 + 0.15 / 0.03),  # reaches v_max: L/v + v/a
    (0.75, 10.0),  # exactly v_max^2/a: triangular with peak v_max
    (0.3, 2 * np.sqrt(0.3 / 0.03)),  # triangular: 2 sqrt(L/a)
])
def test_trapezoid_duration_known_answers(L, duration):
    assert trapezoid(L, 0.15, 0.03).duration_s == pytest.approx(duration, rel=1e-12)


@pytest.mark.parametrize("L", [0.01, 0.5, 0.75, 2.0, 7.3])
def test_profile_integrates_to_length_within_limits(L):
    prof = trapezoid(L, 0.15, 0.03)
    b = prof.phase_bounds()
    t = np.linspace(0, prof.duration_s, 20001)
    phase = np.clip(np.searchsorted(b, t, side="right") - 1, 0, 2)
    s, sd, sdd = (np.choose(phase, [prof.phase_state(k, t)[i] for k in range(3)]) for i in range(3))
    assert np.trapezoid(sd, t) == pytest.approx(L, rel=1e-6)  # independent of the s formula
    assert np.trapezoid(sdd, t) == pytest.approx(0, abs=3 * 0.03 * (t[1] - t[0]))  # rest to rest (jumps: O(a dt))
    assert sd[0] == 0 and sd[-1] == pytest.approx(0, abs=1e-12)
    assert s[0] == 0 and s[-1] == pytest.approx(L, rel=1e-12)
    assert np.all(np.diff(s) >= -1e-15) and sd.max() <= 0.15 + 1e-12 and np.abs(sdd).max() <= 0.03 + 1e-12
    for k in (1, 2):  # s and sd continuous across phase boundaries
        for i in (0, 1):
            assert prof.phase_state(k - 1, b[k])[i] == pytest.approx(prof.phase_state(k, b[k])[i], abs=1e-12)


def test_samples_follow_the_polyline_with_consistent_derivatives():
    wp = np.array([[0, 0, 0], [1, 0, 0], [1, 0.5, 0.5], [3, 2, 1.0]])
    tl = sample_segments(wp, 0.15, 0.03, 0.05)
    assert np.all(np.diff(tl.t_s) >= 0)
    for k in range(3):
        rows = tl.segment == k
        d = wp[k + 1] - wp[k]
        rel = tl.p[rows] - wp[k]
        assert np.allclose(np.cross(rel, d), 0, atol=1e-12)  # on the segment
        assert np.allclose(tl.p[rows][[0, -1]], wp[[k, k + 1]], atol=1e-12)
        assert np.allclose(tl.v[rows][[0, -1]], 0, atol=1e-12)  # rest to rest
    # central differences inside each phase: v = dp/dt, a = dv/dt
    for k in range(3):
        for ph in range(3):
            rows = np.flatnonzero((tl.segment == k) & (tl.phase == ph))
            if len(rows) < 3:
                continue
            t, p, v = tl.t_s[rows], tl.p[rows], tl.v[rows]
            dp = (p[2:] - p[:-2]) / (t[2:] - t[:-2])[:, None]
            dv = (v[2:] - v[:-2]) / (t[2:] - t[:-2])[:, None]
            assert np.allclose(dp, v[1:-1], atol=1e-9)
            assert np.allclose(dv, tl.a[rows][1:-1], atol=1e-9)
    assert tl.t_s[-1] == pytest.approx(sum(p.duration_s for p in tl.profiles))


def test_bad_timing_inputs_are_one_line_errors():
    with pytest.raises(CapmapError, match="must be > 0"):
        trapezoid(1.0, 0.0, 0.03)
    with pytest.raises(CapmapError, match="dt_s"):
        sample_segments(np.array([[0, 0, 0], [1, 0, 0.0]]), 0.15, 0.03, 0)


@pytest.mark.parametrize("L, v, a, j", [(0.001, 0.15, 0.03, 0.01), (0.05, 0.15, 0.03, 0.01), (4.77, 0.15, 0.03, 0.01),
                                        (0.5, 1.0, 4.0, 40.0), (0.05, 1.0, 4.0, 40.0), (3.0, 1.0, 4.0, 5.0)])
def test_scurve_reaches_the_end_at_rest_within_all_limits(L, v, a, j):
    c = scurve(L, v, a, j)
    t = np.linspace(0, c.duration_s, 200001)
    s, sd, sdd = c.evaluate(t)
    assert s[-1] == pytest.approx(L, abs=1e-12) and abs(sd[-1]) < 1e-12 and abs(sdd[-1]) < 1e-9
    assert sd.max() <= v + 1e-12 and np.abs(sdd).max() <= a + 1e-12
    dt = t[1] - t[0]
    assert np.abs(np.diff(sdd)).max() <= j * dt * (1 + 1e-6)  # jerk
    assert np.trapezoid(sd, t) == pytest.approx(L, rel=1e-6)  # s consistent with sd
    assert np.all(np.diff(s) >= -1e-15)
    # time-optimal shape: some limit is active (v_max reached, or a_max, or the jerk alone)
    assert c.v_peak_mps == pytest.approx(v) or c.a_peak_mps2 == pytest.approx(a) or c.durations_s.size <= 4
