"""The reconfiguration figures tell their result from the data: each method's manipulability verdict in the
title with honest units and the kink of dm/dt explained, joint rates one panel per method and arm with one
colour per joint number, and the passive joint (prescribed, so the same for every method that keeps its
time) drawn once against its ranges with the loop closure against its tolerance in words. Synthetic tables;
the figures' texts read from the figure objects."""

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


def _texts(fig) -> str:
    out = [fig._suptitle.get_text()] + [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        legend = ax.get_legend()
        out += [ax.get_title(), ax.get_ylabel()] + ([t.get_text() for t in legend.get_texts()] if legend else [])
    return "\n".join(out + [t.get_text() for leg in fig.legends for t in leg.get_texts()])


def test_manipulability_title_gives_each_methods_verdict_and_the_units(figures, tmp_path):
    rp.manipulability({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "m.png")
    fig = figures[0]
    title = fig._suptitle.get_text()
    assert "long side (arm2.J6 → arm1.J6–J5) while arm1.P1 reconfigures" in title
    assert "null-space method: m 70 → 90, never falling" in title
    assert "pseudo-inverse: m 70 → 40, falling in" in title
    text = _texts(fig)
    assert "6 × 3 Jacobian, rows v [m/rad] and ω [rad/rad]" in text and "[m³]" in fig.axes[0].get_ylabel()
    assert "q̇ = J⁺ẋ + κ (I − J⁺J) ∇m" in text  # the methods' laws, not "kappa grad m"
    assert "σ_min (start → lowest → end)" in fig.axes[1].get_title() and "[–]" not in text


def test_the_kink_of_dm_dt_is_where_the_null_space_gain_returns_to_its_floor(figures, tmp_path):
    ns = _run("nullspace", True)
    ns["kappa_floor"] = 1e-4 * np.sin(np.pi * ns.t_s / 10.0)
    ns["kappa"] = ns.kappa_floor + np.where(ns.t_s < 6.0, 5e-5, 0.0)  # the task alone lowers m until 6 s
    rp.manipulability({"nullspace": ns, "pinv": _run("pinv", False)}, tmp_path / "m.png")
    dm = figures[0].axes[2]
    assert "until 6.0 s the task alone would lower m" in dm.get_title() and len(dm.collections) == 1
    rp.joint_rates({"nullspace": ns, "pinv": _run("pinv", False)}, tmp_path / "r.png")
    assert "(until 6.0 s:\nthe kink)" in _texts(figures[1])


def test_rates_one_panel_per_method_and_arm_one_colour_per_joint_number(figures, tmp_path):
    rp.joint_rates({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "r.png")
    fig = figures[0]
    assert len(fig.axes) == 4  # (null-space, pseudo-inverse) x (arm2, arm1)
    assert fig.axes[0].get_title().startswith("null-space method, arm2")
    assert "(arm1.J5, 83.3 % of its limit)" in fig.axes[1].get_title()
    curves = lambda ax: [ln for ln in ax.lines if len(set(ln.get_ydata())) > 1]  # noqa: E731
    j6_arm2, (j6_arm1, j5_arm1) = curves(fig.axes[0])[0], curves(fig.axes[1])
    assert j6_arm2.get_color() == j6_arm1.get_color() != j5_arm1.get_color()
    assert [t.get_text() for t in fig.legends[0].get_texts()][:2] == ["J5", "J6"]
    title = fig._suptitle.get_text()
    assert "within the rate limits" in title and "arm1.J6 = arm2.J6 throughout" in title


def test_the_passive_joint_is_drawn_once_when_the_methods_move_it_alike(figures, tmp_path):
    rp.passive_joint({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "p.png")
    fig = figures[0]
    theta = fig.axes[0]
    assert len(fig.axes) == 2  # theta and d against their ranges; the closure in one line of text
    assert len([ln for ln in theta.lines if len(set(ln.get_ydata())) > 1]) == 1  # one law, two range lines
    assert "the same for both methods by construction" in fig._suptitle.get_text()
    assert "margin ≥ 50 deg" in theta.get_title()
    closure = _texts(fig)
    assert "stays closed in every run: loop-closure error ≤ 2e-15 m and 2e-16 rad" in closure
    assert "within the tolerance of 1e-9 m and 1e-9 rad" in closure
    stopped = _run("pinv", False, t_end=6.0)
    rp.passive_joint({"nullspace": _run("nullspace", True), "pinv": stopped}, tmp_path / "q.png")
    assert len([ln for ln in figures[1].axes[0].lines if len(set(ln.get_ydata())) > 1]) == 2
    assert "move it differently" in figures[1]._suptitle.get_text()
