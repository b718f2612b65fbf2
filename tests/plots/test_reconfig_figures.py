"""The reconfiguration figures tell their result from the data in one-line headlines and plain words (the formulas
are in the captions): each method's manipulability verdict, where the null-space method pushes back against the
task (the shading's legend in the panel it shades), joint rates one panel per method and arm with one colour per
joint number and each arm's joints in its own legend, and the passive joint (prescribed, so the same for every
method that keeps its time) drawn once against its ranges, its margins and the loop's closure in the headline.
Synthetic tables; the figures' texts read from the figure objects."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import capmap.plots.reconfig as rp
from tests.plots.figures import figure_texts, keep_figures


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions would save, kept open for reading."""
    yield from keep_figures(monkeypatch, rp)


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


def test_manipulability_title_gives_each_methods_verdict_in_one_line(figures, tmp_path):
    rp.manipulability({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "m.png")
    fig = figures[0]
    assert fig._suptitle.get_text() == "Manipulability m: null-space method 70 → 90, never falling; pseudo-inverse 70 → 40"
    text = figure_texts(fig)
    assert "[m³]" in fig.axes[0].get_ylabel()
    assert "lowest 0.5 (null-space method), 0.29 (pseudo-inverse)" in fig.axes[1].get_title()
    assert "κ" not in text and "J⁺" not in text and "kink" not in text  # the formulas: in the caption
    assert fig.axes[0].get_legend() and not fig.axes[2].get_legend()  # nothing shaded: no shading entry


def test_the_shading_says_where_the_null_space_method_pushes_back_in_its_own_panel(figures, tmp_path):
    ns = _run("nullspace", True)
    ns["kappa_floor"] = 1e-4 * np.sin(np.pi * ns.t_s / 10.0)
    ns["kappa"] = ns.kappa_floor + np.where(ns.t_s < 6.0, 5e-5, 0.0)  # the task alone lowers m until 6 s
    rp.manipulability({"nullspace": ns, "pinv": _run("pinv", False)}, tmp_path / "m.png")
    top, dm = figures[0].axes[0], figures[0].axes[2]
    assert dm.get_title() == "until 6 s the task alone would lower m; the null-space method pushes back"
    assert len(dm.collections) == 1 and len(top.collections) == 0
    assert [t.get_text() for t in dm.get_legend().get_texts()] == ["null-space method pushing back"]
    assert "pushing back" not in "".join(t.get_text() for t in top.get_legend().get_texts())
    rp.joint_rates({"nullspace": ns, "pinv": _run("pinv", False)}, tmp_path / "r.png")
    assert "null-space method\npushing back (until 6 s)" in figure_texts(figures[1])


def test_rates_one_panel_per_method_and_arm_each_arm_its_own_joints_legend(figures, tmp_path):
    rp.joint_rates({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "r.png")
    fig = figures[0]
    assert len(fig.axes) == 4  # (null-space, pseudo-inverse) x (arm2, arm1)
    assert fig.axes[0].get_title().startswith("null-space method, arm2")
    assert fig.axes[1].get_title() == "null-space method, arm1: peak 83 % of the limit (J5)"
    curves = lambda ax: [ln for ln in ax.lines if len(set(ln.get_ydata())) > 1]  # noqa: E731
    j6_arm2, (j5_arm1, j6_arm1) = curves(fig.axes[0])[0], curves(fig.axes[1])
    assert j6_arm2.get_color() == j6_arm1.get_color() != j5_arm1.get_color()
    legends = [[t.get_text() for t in ax.get_legend().get_texts()] for ax in fig.axes[2:]]
    assert legends == [["J6"], ["J5", "J6"]]  # each arm's joints, under its column
    assert "arm1.J6 turns as arm2.J6\n(drawn in both)" in [t.get_text() for t in fig.legends[0].get_texts()]
    assert fig._suptitle.get_text() == ("Joint rates stay within their limits: peak 83 % (null-space method), "
                                        "33 % (pseudo-inverse)")


def test_the_passive_joint_is_one_story_in_one_line(figures, tmp_path):
    rp.passive_joint({"nullspace": _run("nullspace", True), "pinv": _run("pinv", False)}, tmp_path / "p.png")
    fig = figures[0]
    theta = fig.axes[0]
    assert len(fig.axes) == 2 and fig.texts == [fig._suptitle]  # theta and d against their ranges; no footnote
    assert len([ln for ln in theta.lines if len(set(ln.get_ydata())) > 1]) == 1  # one law, two range lines
    assert fig._suptitle.get_text() == ("Passive joint arm1.P1 stays at least 50° / 0.2 m inside its ranges; "
                                        "the loop stays closed (< 1e-14 m)")
    assert theta.get_title() == "rotation θ: 0 → 40°, range −90 to 90°"
    stopped = _run("pinv", False, t_end=6.0)
    rp.passive_joint({"nullspace": _run("nullspace", True), "pinv": stopped}, tmp_path / "q.png")
    assert len([ln for ln in figures[1].axes[0].lines if len(set(ln.get_ydata())) > 1]) == 2
    assert figures[1]._suptitle.get_text().endswith("; the methods move it differently")
    opened = _run("pinv", False)
    opened["closure_pos_err_m"] = 2e-6
    rp.passive_joint({"nullspace": _run("nullspace", True), "pinv": opened}, tmp_path / "o.png")
    assert "the loop opens (up to 2e-06 m, 2e-16 rad)" in figures[2]._suptitle.get_text()
