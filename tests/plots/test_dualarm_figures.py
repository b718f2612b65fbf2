"""The dual-arm figures and both MeshCat animations, on small synthetic tables: every legend beside its axes
(never on a curve or a limit line), the verdicts in the titles, µm not "um", and the animations' title, legend and
simulated-time readout in the HTML."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import capmap.plots.dualarm as da
from capmap.plots import reconfig
from capmap.plots.scene3d import Overlay, facing

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
    da.constraint_errors(traj, "x.png", 5e-8)
    da.distances(traj, fine, 0.005, traj.attrs["capmap"]["active"], 5e-8, "x.png")
    da.joints(traj, traj.attrs["capmap"], "q", "x.png")
    da.joints(traj, traj.attrs["capmap"], "qd", "x.png")
    da.torques(tq, {"joints": ARMS, "effort_nm": [50.0] * 14, "panel_kg": 1.8}, 7.0, "x.png")
    da.convergence(outer, "x.png", 5e-8, (2.1e-8, 1.5e-8))
    titles = [fig._suptitle.get_text() for fig in figures]
    for fig in figures:
        _beside(fig)
    errors, distance, joints, velocities, torques, convergence = titles
    # one tolerance decides (the solver's, as in convergence.png), the spec's 7e-7 m named with its source
    assert "held at every node, within the solver's tolerance 5e-08" in errors and "the spec's 7e-7 m" in errors
    legend = [t.get_text() for t in figures[0].axes[0].get_legend().get_texts()]
    assert any("docs/spec/dual-arm-assembly.md" in t for t in legend) and not any("1e-6" in t for t in legend)
    assert "collision-free" in distance and "0.66 µm under it" in distance and " um" not in distance
    assert "all within their limits" in joints and "all within their limits" in velocities
    assert "within the effort limits" in torques and "peak" in torques and "best internal force" in torques
    assert "converged" in convergence and "≤ tolerance 5e-08" in convergence and "feasibility-driven DDP" in convergence
    assert "m or rad]" not in figures[5].axes[0].get_ylabel()
    # the velocities are zoomed to the data, their limits drawn on a full-scale gauge beside them
    ax, gauge = figures[3].axes[:2]
    assert any(np.allclose(line.get_ydata(), 100) for line in gauge.get_lines()) and gauge.get_ylim()[1] > 100
    assert ax.get_ylim()[1] < 10  # 3 % of the limit at most: zoomed
    # the marker sits on the curve it names
    ax = next(a for a in figures[3].axes if "closest to a limit" in [line.get_label() for line in a.get_lines()])
    marker = next(line for line in ax.get_lines() if line.get_label() == "closest to a limit")
    name = next(t.get_text() for t in ax.texts if t.get_text() in ARMS)
    named = next(line for line in ax.get_lines() if line.get_label().startswith(name + ":"))
    assert name in velocities
    assert np.isclose(marker.get_ydata()[0], np.interp(marker.get_xdata()[0], named.get_xdata(), named.get_ydata()))


def test_a_limit_passed_is_said_so(figures, traj):
    traj.loc[30, "q_left_s0_rad"] = 1.8  # beyond its upper limit (1.7 rad)
    da.joints(traj, traj.attrs["capmap"], "q", "x.png")
    assert "LIMIT IS EXCEEDED" in figures[0]._suptitle.get_text()
    traj.loc[80, "path_err_m"] = 1e-6  # beyond the solver's tolerance and the spec's 7e-7 m
    da.constraint_errors(traj, "x.png", 5e-8)
    assert "NOT HELD" in figures[1]._suptitle.get_text()


def test_no_curve_hides_under_a_larger_one(figures, traj):
    tq = pd.DataFrame({"t_s": traj.t_s} | {f"tau_{n}_nm": (k + 1) * (1 + 0 * traj.t_s) for k, n in enumerate(ARMS)}
                      | {f"tau_best_{n}_nm": 1 + 0 * traj.t_s for n in ARMS})
    da.torques(tq, {"joints": ARMS, "effort_nm": [50.0] * 14, "panel_kg": 1.8}, 7.0, "x.png")
    curves = [line for line in figures[0].axes[0].get_lines() if line.get_label().startswith("left_")]
    peaks = [line.get_ydata().max() for line in curves]
    assert np.argsort([line.get_zorder() for line in curves]).tolist() == np.argsort(peaks)[::-1].tolist()
    assert "left_s0: peak 2 %" in curves[0].get_label()  # its peak in the legend, however small


def test_the_walls_facing_the_camera_are_cut_away():
    tri = np.array([[[0, -1, 0], [1, -1, 0], [0, -1, 1]], [[0, 1, 0], [1, 1, 0], [0, 1, 1]]], float)
    assert facing(tri, np.array(["near", "far"]), np.zeros(3), np.array([0, -2.0, 0.5])).tolist() == [True, False]


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
    caption = Overlay("Baxter carries a panel", ("smallest safety distance 5.00 mm",), frame_text=("f0", "f1", "f2"))
    held = da.Held(1, np.eye(4), np.array([0.01, 0.2, 0.1]), np.array([[0.05, 0.0]]), 0.01, np.eye(4),
                   ((np.array([0.1, 0.05, 0]), np.array([0.0, 0.05, 0]), 0.008),))
    da.animation(caps, poses, held, env, 25.0, caption, tmp_path / "a.html")
    html = (tmp_path / "a.html").read_text()
    assert "Baxter carries a panel" in html and "smallest safety distance 5.00 mm" in html
    assert "Baxter&#x27;s arms" in html and "held by both grippers" in html and "the 1 pins" in html
    assert "final pose on the pins" in html and "capmap-time" in html and '["f0", "f1", "f2"]' in html


def test_the_reconfiguration_animation_carries_title_legend_and_time(tmp_path):
    links = ("a1.boom", "a1.ee", "a2.link", "a3.link")
    frames = {m: np.tile(np.eye(4), (4, 4, 1, 1)) for m in ("nullspace", "pinv")}
    frames["pinv"][2:, 2, 0, 3] = 0.5  # the runs part at frame 2
    segments = [("a1.boom", np.zeros(3), np.array([0, 0, 1.0])), ("a2.link", np.zeros(3), np.array([1.0, 0, 0])),
                ("a3.link", np.zeros(3), np.array([0, 1.0, 0]))]
    m = {"nullspace": np.array([1.0, 1.5, 2.0, 2.0]), "pinv": np.array([1.0, 0.9, 0.8, 0.8])}
    motion = reconfig.ReconfigMotion(links, frames, m, 2.0, "a1.boom", ("a1.ee", "a2.ee"))
    reconfig.animation(motion, segments, "robot: boom unlocked\nnull-space: m 1 → 2", tmp_path / "r.html")
    html = (tmp_path / "r.html").read_text()
    assert "robot: boom unlocked" in html and "null-space: m 1 → 2" in html and "capmap-time" in html
    assert "pseudo-inverse run, 1.5 s" in html and "capture: a1.ee held by a2.ee" in html and "a3: not in the loop" in html
    # the live readout: each run's manipulability per frame, and how far apart the runs are
    assert "manipulability m: null-space 1.0 (+0 %), pseudo-inverse 1.0 (+0 %); the runs&#x27; joints up to 0.00" not in html
    assert "null-space 2.0 (+100 %), pseudo-inverse 0.8 (-20 %); the runs' joints up to 0.50 m apart" in html
