"""The reconfiguration figures tell their result from the data: each method's manipulability verdict in the
title, identical joint rates drawn once, and the passive joint (prescribed, so the same for every method
that keeps its time) drawn once against its ranges beside the loop-closure error of each method. Synthetic
tables; the figures' texts read from the figure objects."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import capmap.plots.reconfig as rp
from capmap.plots.common import plt


@pytest.fixture
def figures(monkeypatch):
    kept = []
    monkeypatch.setattr(rp, "save", lambda fig, out_png, rect=None: kept.append(fig))
    yield kept
    for fig in kept:
        plt.close(fig)


def _run(method: str, rising: bool, t_end: float = 10.0) -> pd.DataFrame:
    t = np.linspace(0.0, t_end, 101)
    law = 3 * (t / 10.0) ** 2 - 2 * (t / 10.0) ** 3
    m = 70.0 + (20.0 if rising else -30.0) * law
    df = pd.DataFrame({"method": method, "t_s": t, "manipulability": m, "dm_dt": np.gradient(m, t),
                       "min_singular_value": m / 140.0, "passive_theta_deg": 40.0 * law, "passive_d_m": 0.6 * law,
                       "qd_arm2_j6_deg_s": np.sin(t / 3), "qd_arm1_j6_deg_s": np.sin(t / 3),
                       "qd_arm1_j5_deg_s": (2.5 if rising else 1.0) * np.sin(t / 5),
                       "closure_pos_err_m": 1e-15 * (1 + law), "closure_rot_err_rad": 1e-16 * (1 + law)})
    df.attrs["capmap"] = {"method": method, "status": "completed", "unlocked": "arm1.P1",
                          "moving_joints": ["arm2.J6", "arm1.J6", "arm1.J5"],
                          "rate_limits_deg_s": {c: 3.0 for c in df.columns if c.startswith("qd_")},
                          "passive_ranges": {"theta_deg": [-90.0, 90.0], "d_m": [-0.5, 0.8]}}
    return df


def test_manipulability_title_gives_each_methods_verdict(figures, tmp_path):
    rp.manipulability({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "m.png")
    title = figures[0]._suptitle.get_text()
    assert "null-space method: m 70 → 90, never falling" in title
    assert "pseudo-inverse: m 70 → 40, falling in" in title and "6 × 3 Jacobian" in title


def test_identical_rates_are_drawn_once_and_the_peak_is_named(figures, tmp_path):
    rp.joint_rates({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "r.png")
    fig = figures[0]
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "arm2.J6 = arm1.J6" in labels and "arm1.J6" not in labels
    assert "(arm1.J5), 83.3 % of its limit" in fig.axes[0].get_title()
    assert "within the rate limits" in fig._suptitle.get_text()


def test_the_passive_joint_is_drawn_once_when_the_methods_move_it_alike(figures, tmp_path):
    rp.passive_joint({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "p.png")
    fig = figures[0]
    theta = fig.axes[0]
    assert len([ln for ln in theta.lines if len(set(ln.get_ydata())) > 1]) == 1  # one law, two range lines
    assert "the same for both methods by construction" in fig._suptitle.get_text()
    assert "margin ≥ 50 deg" in theta.get_title()
    closure = fig.axes[1]
    assert closure.get_yscale() == "log" and len(closure.lines) == 2  # one per method
    stopped = _run("pinv", False, t_end=6.0)
    rp.passive_joint({"nullspace": _run("nullspace", True), "pinv": stopped}, tmp_path / "q.png")
    assert len([ln for ln in figures[1].axes[0].lines if len(set(ln.get_ydata())) > 1]) == 2
    assert "move it differently" in figures[1]._suptitle.get_text()
