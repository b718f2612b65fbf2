"""The dual-arm figures and both MeshCat animations, on small synthetic tables: every legend beside its axes
(never on a curve or a limit line), each verdict in a one-line title free of file names and config keys, µm not "um",
and the animations' title, foldable legend, simulated-time readout and live inset in the HTML."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import capmap.plots.dualarm as da
import capmap.plots.dualarm_motion as dm
import capmap.plots.dualarm_scene as ds
from capmap.plots import reconfig
from capmap.plots.scene3d import Inset, Overlay, facing
from tests.plots.figures import keep_figures

ARMS = [f"{s}_{j}" for s in ("left", "right") for j in ("s0", "s1", "e0", "e1", "w0", "w1", "w2")]


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions would save, kept open for reading."""
    yield from keep_figures(monkeypatch, da, dm)


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
    fine.loc[80, "min_distance_m"] = 0.005 + 2e-7  # a second touch of the margin, at 8 s
    tq = pd.DataFrame({"t_s": traj.t_s} | {f"tau_{n}_nm": 20 * np.cos(traj.t_s / 10 + k) for k, n in enumerate(ARMS)}
                      | {f"tau_best_{n}_nm": 10 + 0 * traj.t_s for n in ARMS})
    outer = pd.DataFrame({"outer": range(4), "eq_violation": [1e-2, 1e-4, 1e-6, 2e-8],
                          "in_violation": [1e-3, 1e-5, 0.0, 1e-10], "mu": [1e2, 1e3, 1e4, 1e5],
                          "inner_iterations": [5, 4, 3, 2]})
    da.constraint_errors(traj, "x.png", 5e-8)
    da.distances(traj, fine, 0.005, traj.attrs["capmap"]["active"], 5e-8, "x.png")
    dm.joints(traj, traj.attrs["capmap"], "x.png")
    dm.velocities(traj, traj.attrs["capmap"], "x.png")
    dm.torques(tq, {"joints": ARMS, "effort_nm": [50.0] * 14, "panel_kg": 1.8}, 7.0, "x.png")
    da.convergence(outer, "x.png", 5e-8, (2.1e-8, 1.5e-8))
    titles = [fig._suptitle.get_text() for fig in figures]
    for fig in figures:
        _beside(fig)
    errors, distance, joints, velocities, torques, convergence = titles
    # each headline one verdict line; no file names or config keys in titles and legends
    words = titles + [t.get_text() for fig in figures for ax in fig.axes if ax.get_legend()
                      for t in ax.get_legend().get_texts()]
    assert not any("\n" in t for t in titles)
    assert not any(w in t for t in words for w in (".png", ".csv", ".md", "dualarm.solver", "config"))
    # one tolerance decides (the solver's, as in convergence.png), the spec's 7e-7 m beside it
    assert "held at every node" in errors and "≤ tolerance 5e-08" in errors and "the spec's 7e-7 m" in errors
    ticks = [t.get_text() for t in figures[0].axes[0].get_yticklabels()]
    assert "0" in ticks  # an exact zero, at the axis' foot
    assert "collision-free" in distance.lower() and " um" not in distance
    assert "0.66 µm under the margin" in figures[1].axes[1].get_title(loc="left")
    # every touch of the margin marked, the second one of a pair too (named with both times)
    legend = [t.get_text() for t in figures[1].axes[0].get_legend().get_texts()]
    assert any("a vs b" in t and "5.00, 8.00 s" in t for t in legend)
    assert "all within their limits" in joints and "all within their limits" in velocities
    assert "within the effort limits" in torques and "peak" in torques
    assert "converged" in convergence and "≤ tolerance 5e-08" in convergence and "FDDP" not in convergence
    # the result's node errors on a tick of their own, on the iteration grid
    ax = figures[5].axes[0]
    result = next(line for line in ax.get_lines() if line.get_label().startswith("result"))
    assert np.allclose(result.get_xdata(), 4) and "result" in [t.get_text() for t in figures[5].axes[1].get_xticklabels()]
    # the velocities at their scale, the ±100 % limits beyond a break, in thin strips above and below
    strips = [a for a in figures[3].axes if any(np.allclose(line.get_ydata(), 100) for line in a.get_lines())]
    assert strips and all(a.get_ylim()[0] > 50 for a in strips)
    ax = next(a for a in figures[3].axes if "closest to a limit" in [line.get_label() for line in a.get_lines()])
    assert ax.get_ylim()[1] < 10  # 3 % of the limit at most: at the data's scale
    # the marker sits on the curve it names
    marker = next(line for line in ax.get_lines() if line.get_label() == "closest to a limit")
    name = next(t.get_text() for t in ax.texts if t.get_text() in ARMS)
    named = next(line for line in ax.get_lines() if line.get_label().startswith(name + ":"))
    assert name in velocities
    assert np.isclose(marker.get_ydata()[0], np.interp(marker.get_xdata()[0], named.get_xdata(), named.get_ydata()))
    # the best internal force, alike for both arms, said once
    labels = [line.get_label() for a in figures[4].axes for line in a.get_lines() if line.get_linestyle() == ":"]
    assert "both arms alike" in labels[0] and labels[1] == "best internal force (as above)"


def test_a_limit_passed_is_said_so(figures, traj):
    traj.loc[30, "q_left_s0_rad"] = 1.8  # beyond its upper limit (1.7 rad)
    dm.joints(traj, traj.attrs["capmap"], "x.png")
    assert "LIMIT IS EXCEEDED" in figures[0]._suptitle.get_text()
    traj.loc[80, "path_err_m"] = 1e-6  # beyond the solver's tolerance and the spec's 7e-7 m
    da.constraint_errors(traj, "x.png", 5e-8)
    assert "NOT HELD" in figures[1]._suptitle.get_text()
    traj.loc[40, "qd_left_s0_rad_s"] = 1.6  # beyond its velocity limit (1.5 rad/s): one axis to the limits, no break
    dm.velocities(traj, traj.attrs["capmap"], "x.png")
    assert "LIMIT IS EXCEEDED" in figures[2]._suptitle.get_text() and len(figures[2].axes) == 2


def test_no_curve_hides_under_a_larger_one(figures, traj):
    tq = pd.DataFrame({"t_s": traj.t_s} | {f"tau_{n}_nm": (k + 1) * (1 + 0 * traj.t_s) for k, n in enumerate(ARMS)}
                      | {f"tau_best_{n}_nm": 1 + 0 * traj.t_s for n in ARMS})
    dm.torques(tq, {"joints": ARMS, "effort_nm": [50.0] * 14, "panel_kg": 1.8}, 7.0, "x.png")
    curves = [line for line in figures[0].axes[0].get_lines() if line.get_label().startswith("left_")]
    peaks = [line.get_ydata().max() for line in curves]
    assert np.argsort([line.get_zorder() for line in curves]).tolist() == np.argsort(peaks)[::-1].tolist()
    assert "left_s0: peak 2 %" in curves[0].get_label()  # its peak in the legend, however small


def test_the_walls_facing_the_camera_are_cut_away():
    tri = np.array([[[0, -1, 0], [1, -1, 0], [0, -1, 1]], [[0, 1, 0], [1, 1, 0], [0, 1, 1]]], float)
    assert facing(tri, np.array(["near", "far"]), np.zeros(3), np.array([0, -2.0, 0.5])).tolist() == [True, False]


def test_the_overlay_escapes_its_words_and_reads_the_animation_time():
    inset = Inset("m <x>", (("run", 0x3070C0, (1.0, 2.0, 3.0)),), 1.0)
    html = Overlay("a <b> & c", ("line",), ((0x3070C0, 0.25, "ghost"),), ("frame </script>",), 25.0, inset, 12.5).markup()
    assert "a &lt;b&gt; &amp; c" in html and "rgba(48,112,192,0.50)" in html and "ghost" in html
    assert "viewer.animator" in html and "simulated time t = " in html and "</script>\"" not in html
    assert '<details id="capmap-legend" open>' in html  # a click folds the legend
    assert "m &lt;x&gt;" in html and "capmap-cursor" in html and "<polyline" in html and "start = 12.5" in html


def test_the_dual_arm_animation_carries_title_legend_and_time(tmp_path):
    poses = np.tile(np.eye(4), (3, 3, 1, 1))
    poses[:, 1, 0, 3] = [0.0, 0.1, 0.2]
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0.2, 0.2, 1], [0.3, 0.2, 1], [0.2, 0.3, 1]]], float)
    env = ds.Surroundings(tri, [(np.zeros(3), np.ones(3), 0.01)], np.array(["floor", "box"], dtype=object))
    caps = [("torso", 0, np.zeros(3), np.array([0, 0, 0.5]), 0.1), ("arm", 1, np.zeros(3), np.array([0.3, 0, 0]), 0.05)]
    caption = Overlay("Baxter carries a panel", ("smallest safety distance 5.00 mm",), frame_text=("f0", "f1", "f2"))
    held = ds.Held(1, np.eye(4), np.array([0.01, 0.2, 0.1]), np.array([[0.05, 0.0]]), 0.01, np.eye(4),
                   ((np.array([0.1, 0.05, 0]), np.array([0.0, 0.05, 0]), 0.008),))
    ds.animation(caps, poses, held, env, 25.0, caption, tmp_path / "a.html")
    html = (tmp_path / "a.html").read_text()
    assert "Baxter carries a panel" in html and "smallest safety distance 5.00 mm" in html
    assert "Baxter&#x27;s arms" in html and "held by both grippers" in html and "1 pins" in html
    assert "final pose on the pins" in html and "capmap-time" in html and '["f0", "f1", "f2"]' in html
    # each solid of the envelope in its own colour, named: the box an obstacle, the floor part of the cabin
    assert "rgba(46,158,90," in html and "box</div>" in html and "cabin</div>" in html


def test_the_reconfiguration_animation_carries_title_legend_and_time(tmp_path):
    links = ("a1.boom", "a1.ee", "a2.link", "a3.link")
    frames = {m: np.tile(np.eye(4), (4, 4, 1, 1)) for m in ("nullspace", "pinv")}
    frames["pinv"][2:, 2, 0, 3] = 0.5  # the runs part at frame 2
    segments = [("a1.boom", np.zeros(3), np.array([0, 0, 1.0])), ("a2.link", np.zeros(3), np.array([1.0, 0, 0])),
                ("a3.link", np.zeros(3), np.array([0, 1.0, 0]))]
    m = {"nullspace": np.array([1.0, 1.5, 2.0, 2.0]), "pinv": np.array([1.0, 0.9, 0.8, 0.8])}
    motion = reconfig.ReconfigMotion(links, frames, m, 2.0, "a1.boom", ("a1.ee", "a2.ee"))
    reconfig.animation(motion, segments, "Robot: m +100 % (null-space) vs −20 % (pseudo-inverse)", tmp_path / "r.html")
    html = (tmp_path / "r.html").read_text()
    assert "Robot: m +100 % (null-space) vs −20 % (pseudo-inverse)" in html and "capmap-time" in html
    assert "pseudo-inverse run, 1.5 s" in html and "capture: a1.ee held by a2.ee" in html and "a3: not in the loop" in html
    # what to watch, from when the runs part; the view opens where they are half their widest apart
    assert "Watch the red sheath (pseudo-inverse) leave the blue arms from 1 s (opens at 1 s)" in html
    assert "start = 1.0" in html
    # the live readout: each run's manipulability per frame, and which joint of the two runs is how far apart
    assert ("null-space 2.0 (+100 %), pseudo-inverse 0.8 (\\u221220 %)\\n"
            "farthest joint: a2.link of the two runs 0.50 m apart") in html
    # and a live plot of m(t), both runs
    assert "manipulability m" in html and html.count("<polyline") == 2
