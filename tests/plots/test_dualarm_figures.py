"""The dual-arm figures and both MeshCat animations, on small synthetic tables: every legend beside its axes
(never on a curve or a limit line), the verdicts in the titles, µm not "um", and the animations' title, legend and
simulated-time readout in the HTML."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import capmap.plots.dualarm as da
from capmap.plots import reconfig
from capmap.plots.scene3d import Overlay

ARMS = [f"{s}_{j}" for s in ("left", "right") for j in ("s0", "s1", "e0", "e1", "w0", "w1", "w2")]


@pytest.fixture
def figures(monkeypatch):
    """The figures the plotting functions make (kept open instead of saved)."""
    made = []
    monkeypatch.setattr(da, "save", lambda fig, out, rect=None: made.append(fig))
    yield made
    for fig in made:
        da.plt.close(fig)


@pytest.fixture
def traj():
    t = np.round(np.arange(0.0, 10.0 + 1e-9, 0.1), 6)
    phase = np.where(t < 7.0, "transfer", "insertion").astype(object)
    phase[t == 7.0], phase[-1] = "pre_insertion", "final"
    cols = {"t_s": t, "node": np.arange(len(t)), "phase": phase}
    for k, n in enumerate(ARMS):
        cols[f"q_{n}_rad"] = 0.3 * np.sin(t / 10 + k)
        cols[f"qd_{n}_rad_s"] = 0.03 * np.cos(t / 10 + k)
    cols |= {"closed_chain_pos_err_m": 1e-9 * (1 + t), "path_err_m": np.where(t < 7, 0.0, 1e-8),
             "closed_chain_rot_err_rad": 1e-10 * (1 + t), "path_err_rad": 1e-9 + 0 * t,
             "min_distance_m": 0.005 + 0.01 * (t - 5) ** 2 / 25, "min_distance_pair": ["a vs b"] * len(t)}
    df = pd.DataFrame(cols)
    df.attrs["capmap"] = {"joints": ARMS, "q_lower": [-1.7] * 14, "q_upper": [1.7] * 14, "v_max": [1.5] * 14,
                          "margin_m": 0.005, "active": [["left_upper_elbow vs strut", 0.005, 5.0, 4.0, 6.0]]}
    return df


def _beside(fig) -> None:
    """Every legend lies outside every axes of its figure."""
    fig.canvas.draw()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    assert legends
    for leg in legends:
        box = leg.get_window_extent()
        assert not any(box.overlaps(ax.get_window_extent()) for ax in fig.axes)


def test_every_figure_keeps_its_legend_off_the_curves_and_says_its_verdict(figures, traj):
    fine = traj[["t_s", "node", "min_distance_m"]].copy()
    fine.loc[50, "min_distance_m"] = 0.005 - 6.6e-7  # between the nodes, 0.66 µm under the margin
    tq = pd.DataFrame({"t_s": traj.t_s} | {f"tau_{n}_nm": 20 * np.cos(traj.t_s / 10 + k) for k, n in enumerate(ARMS)}
                      | {f"tau_best_{n}_nm": 10 + 0 * traj.t_s for n in ARMS})
    outer = pd.DataFrame({"outer": range(4), "eq_violation": [1e-2, 1e-4, 1e-6, 2e-8],
                          "in_violation": [1e-3, 1e-5, 0.0, 1e-10], "mu": [1e2, 1e3, 1e4, 1e5],
                          "inner_iterations": [5, 4, 3, 2]})
    da.constraint_errors(traj, "x.png")
    da.distances(traj, fine, 0.005, traj.attrs["capmap"]["active"], "x.png")
    da.joints(traj, traj.attrs["capmap"], "q", "x.png")
    da.joints(traj, traj.attrs["capmap"], "qd", "x.png")
    da.torques(tq, {"joints": ARMS, "effort_nm": [50.0] * 14, "panel_kg": 1.8}, 7.0, "x.png")
    da.convergence(outer, "x.png", 5e-8)
    titles = [fig._suptitle.get_text() for fig in figures]
    for fig in figures:
        _beside(fig)
    errors, distance, joints, velocities, torques, convergence = titles
    assert "≤ 7e-7 m" in errors and "held" in errors
    assert "collision-free" in distance and "0.66 µm under the margin" in distance and " um" not in distance
    assert "all within their limits" in joints and "all within their limits" in velocities
    assert "within the effort limits" in torques and "peak" in torques
    assert "converged" in convergence and "≤ tolerance 5e-08" in convergence
    # the velocity limits are drawn even when the motion stays far below them
    assert any(np.allclose(line.get_ydata(), 100) for line in figures[3].axes[0].get_lines())


def test_a_limit_passed_is_said_so(figures, traj):
    traj.loc[30, "q_left_s0_rad"] = 1.8  # beyond its upper limit (1.7 rad)
    da.joints(traj, traj.attrs["capmap"], "q", "x.png")
    assert "LIMIT IS EXCEEDED" in figures[0]._suptitle.get_text()


def test_the_overlay_escapes_its_words_and_reads_the_animation_time():
    html = Overlay("a <b> & c", ("line",), ((0x3070C0, 0.25, "ghost"),), ("frame </script>",), 25.0).markup()
    assert "a &lt;b&gt; &amp; c" in html and "rgba(48,112,192,0.25)" in html and "ghost" in html
    assert "viewer.animator" in html and "simulated time t = " in html and "</script>\"" not in html


def test_the_dual_arm_animation_carries_title_legend_and_time(tmp_path):
    poses = np.tile(np.eye(4), (3, 3, 1, 1))
    poses[:, 1, 0, 3] = [0.0, 0.1, 0.2]
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 1], [1, 0, 1], [0, 1, 1]]], float)
    env = da.Surroundings(tri, [(np.zeros(3), np.ones(3), 0.01)], np.array(["floor", "box"], dtype=object))
    caps = [("torso", 0, np.zeros(3), np.array([0, 0, 0.5]), 0.1), ("arm", 1, np.zeros(3), np.array([0.3, 0, 0]), 0.05)]
    caption = Overlay("baxter: scene", ("smallest safety distance 5.00 mm",), frame_text=("f0", "f1", "f2"))
    da.animation(caps, poses, (1, np.eye(4), (0.01, 0.2, 0.1)), env, 25.0, caption, tmp_path / "a.html")
    html = (tmp_path / "a.html").read_text()
    assert "baxter: scene" in html and "smallest safety distance 5.00 mm" in html
    assert "Baxter&#x27;s arms" in html and "the panel, held by both grippers" in html
    assert "capmap-time" in html and '["f0", "f1", "f2"]' in html


def test_the_reconfiguration_animation_carries_title_legend_and_time(tmp_path):
    frames = {m: np.tile(np.eye(4), (4, 2, 1, 1)) for m in ("nullspace", "pinv")}
    segments = [("boom", np.zeros(3), np.array([0, 0, 1.0])), ("link", np.zeros(3), np.array([1.0, 0, 0]))]
    reconfig.animation(("boom", "link"), segments, frames, 2.0, "boom", "robot: boom unlocked\nnull-space: m 1 → 2",
                       tmp_path / "r.html")
    html = (tmp_path / "r.html").read_text()
    assert "robot: boom unlocked" in html and "null-space: m 1 → 2" in html
    assert "pseudo-inverse (translucent ghost): arms, 1.5 s" in html and "platform" in html and "capmap-time" in html
