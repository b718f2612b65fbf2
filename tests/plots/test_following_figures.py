"""The following figures tell their result from the data in one-line headlines: the case's payload and path, the
follower's gap to TOPP-RA and where it comes from (split only when both parts add time; TOPP-RA's own need of a limit
when it exceeds one), the binding joint on its own limit and the others in % of theirs, which limits were tightened
for the case, the follower's stops marked, no panel for a joint that carries next to nothing (named instead), a
drive split only for a robot with drives, and a readable figure for a path that cannot be followed. Numbers rounded
to what a reader needs. Synthetic tables; the figures' texts read from the figure objects."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import capmap.plots.following as fp
import capmap.plots.following_limits as fl
from tests.plots.figures import figure_texts, keep_figures

LIMITS = {"tau_j1_nm": 10.0, "tau_j2_nm": 100.0, "tau_j3_nm": 50.0}


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions would save, kept open for reading."""
    yield from keep_figures(monkeypatch, fp, fl)


def _tables(terms: str = "links+armature+coulomb+viscous"):
    """A follower run of 12 s (joint 1 at its limit from 2 to 5 s, joint 3 unloaded) and TOPP-RA's of 10 s."""
    t = np.linspace(0.0, 12.0, 1201)
    s = 0.5 * (1 - np.cos(np.pi * t / 12.0))
    limited = (t >= 2.0) & (t <= 5.0)
    ts = pd.DataFrame({"case": "ground", "segment": (t > 6.0).astype(int), "t_s": t, "s_cmd_m": np.minimum(1.05 * s, 1.0),
                       "sd_cmd_mps": np.gradient(s, t), "s_m": s, "sd_mps": np.gradient(s, t),
                       "sdd_mps2": np.gradient(np.gradient(s, t), t), "lag_m": 0.01 * s * (1 - s),
                       "limited": limited, "infeasible": False, "deviation_m": 1e-9 + 0 * t, "deviation_rad": 1e-10 + 0 * t})
    tau1 = np.where(limited, 10.0, 4.0 * np.sin(t))
    for col, tau in (("tau_j1_nm", tau1), ("tau_j2_nm", 30.0 * np.cos(t)), ("tau_j3_nm", 0.0 * t)):
        ts[col] = tau
        ts[col.replace("tau_", "tau_cmd_")] = np.where(limited, 1.5, 1.0) * tau
        drives = terms != "links"
        ts[col.replace("tau_", "tau_armature_")] = 0.1 * tau if drives else 0.0
        ts[col.replace("tau_", "tau_friction_")] = 0.2 * tau if drives else 0.0
    tt = np.linspace(0.0, 10.0, 1001)
    tp = pd.DataFrame({"case": "ground", "segment": 0, "t_s": tt, "s_m": 0.5 * (1 - np.cos(np.pi * tt / 10.0)),
                       "sd_mps": 0.05 * np.pi * np.sin(np.pi * tt / 10.0),
                       "tau_j1_nm": np.where(tt < 8.0, 10.0, -10.0), "tau_j2_nm": 30.0 * np.cos(tt), "tau_j3_nm": 0.0 * tt})
    ts.attrs["capmap"] = {"case": "ground", "terms": terms, "torque_limits_nm": LIMITS}
    return ts, tp


def _config(ts, **run):
    """The run's configuration in the table's metadata, as the follow stage stores it."""
    ts.attrs["capmap"]["config"] = {"run": run}
    return ts


def test_progress_says_what_is_followed_and_splits_the_gap_to_toppra(figures, tmp_path):
    ts, tp = _tables()
    _config(ts, follow={"ground": {"v_max_mps": 0.2, "joint_torque_nm": [10, 100, 50]}})
    summary = {"command_duration_s": 10.97, "payload_kg": 2.0, "path": "straight line"}
    fp.follow_progress(ts, tp, LIMITS, "ground", tmp_path / "p.png", summary)
    title, text = figures[0]._suptitle.get_text(), figure_texts(figures[0])
    assert "\n" not in title  # one line
    assert title == ("ground, 2 kg on the straight line: follower 12.0 s, 20 % longer than TOPP-RA (10.0 s): "
                     "0.97 s from its jerk limit, 1.0 s from the torque limits")
    assert "jerk limit: +0.97 s" in text and "torque limits: +1.0 s" in text  # the brackets: both parts add time
    assert "S-curve command, jerk-limited (11.0 s): needs 150 % of joint 1's limit" in text
    assert "speed limit 0.2 m/s" in text and "v_max_mps" not in text  # the config key: in the caption
    assert any(ln.get_ydata()[0] == 0.2 and len(set(ln.get_ydata())) == 1 for ln in figures[0].axes[1].lines)
    assert "never off it" in text and "µm" not in text and "arcsec" not in text
    assert len(figures[0].axes) == 3


def test_progress_says_almost_all_and_a_negative_part_in_words(figures, tmp_path):
    ts, tp = _tables()
    fp.follow_progress(ts, tp, LIMITS, "space", tmp_path / "p.png", {"command_duration_s": 11.95})
    assert figures[0]._suptitle.get_text().endswith("almost all from its jerk limit")
    fp.follow_progress(ts, tp, LIMITS, "space", tmp_path / "q.png", {"command_duration_s": 9.99})
    title, top = figures[1]._suptitle.get_text(), figures[1].axes[0]
    assert "from its" not in title and not top.texts  # no split with a negative part: in words over the panel
    assert top.get_title() == ("its command alone would finish 0.01 s before TOPP-RA (it ignores the torque limits); "
                               "the torque limits add 2.0 s")


def test_progress_says_when_toppra_exceeds_a_limit_under_the_full_model(figures, tmp_path):
    ts, tp = _tables()
    tp["tau_j1_nm"] *= 1.15  # TOPP-RA's torques measured with a term its own model lacks
    fp.follow_progress(ts, tp, LIMITS, "ground", tmp_path / "p.png",
                       {"follower_terms": "links+armature+coulomb+viscous", "toppra_terms": "links+armature+coulomb"})
    assert figures[0]._suptitle.get_text().endswith(
        "than TOPP-RA (10.0 s), which ignores viscous friction and would need 115 % of joint 1's limit")
    fp.follow_progress(ts, tp, LIMITS, "ground", tmp_path / "q.png")  # no summary row: the command's time from the rows
    assert "would need 115 % of joint 1's limit" in figures[1]._suptitle.get_text()


def test_torques_draw_the_binding_joint_on_its_own_limit_and_the_rest_in_percent(figures, tmp_path):
    ts, _ = _tables()
    ts["tau_j3_nm"] = ts["tau_cmd_j3_nm"] = 4.0 * np.sin(ts.t_s)  # joint 3 under 10 % of its limit: named, not drawn
    _config(ts, failure={"joint": 7, "angle_deg": 100})
    fl.follow_torques(ts, LIMITS, "space", tmp_path / "t.png", {c: 2 * v for c, v in LIMITS.items()})
    fig = figures[0]
    joint1, rest = fig.axes[0], fig.axes[1]
    assert joint1.get_title().startswith("joint 1 (±10 N m, derated on purpose from 20 N m so the follower must limit it)")
    assert len(joint1.collections) == 1  # at its limit: shaded
    flat = lambda ax: sorted(ln.get_ydata()[0] for ln in ax.lines if len(set(ln.get_ydata())) == 1)  # noqa: E731
    assert flat(joint1) == [-10.0, 10.0] and flat(rest) == [-100.0, 100.0]  # its limit; the others' in %
    assert rest.get_title() == ("the other joints, in % of their limits "
                                "(not drawn: joint 7 locked, joint 3 below 10 % of its limit)")
    assert [t.get_text() for t in rest.get_legend().get_texts()] == ["joint 2 (±100 N m)"]
    title = fig._suptitle.get_text()
    assert title == "space: the follower keeps every torque limit; its command would need 150 % of joint 1's"
    fl.follow_torques(ts, {c: 10.0 for c in LIMITS}, "space", tmp_path / "u.png", {c: 700.0 for c in LIMITS})
    assert figures[1]._suptitle.get_text().endswith("; limits 10 N m (tightened for this case)")
    assert "derated" not in figure_texts(figures[1])


def test_the_followers_stops_at_the_waypoints_are_marked_and_explained(figures, tmp_path):
    ts, _ = _tables()
    k = int(np.flatnonzero(ts.segment.to_numpy() == 0)[-1]) - 3  # segment 1 ends in a crawl braked in one period
    ts.loc[k - 5:k, "sd_mps"], ts.loc[k + 1:k + 3, "sd_mps"] = 1e-6, 0.0
    ts.loc[k - 5:k, "sdd_mps2"], ts.loc[k, "sdd_mps2"] = 1e-5, -1e-3
    ts.loc[k, "tau_j1_nm"] = -9.0  # its torque pulse
    fl.follow_torques(ts, LIMITS, "ground", tmp_path / "t.png")
    marks = [ln for ln in figures[0].axes[0].lines if ln.get_marker() == "o"]
    assert len(marks) == 1 and marks[0].get_ydata()[0] == -9.0
    assert "stop at a waypoint: braking pulse ≤ 1 ms, within the limit" in figure_texts(figures[0])
    ts.loc[k, "tau_j1_nm"] = -10.0  # a pulse at the limit: said so, in the same one line
    fl.follow_torques(ts, LIMITS, "ground", tmp_path / "u.png")
    assert "stop at a waypoint: braking pulse ≤ 1 ms, never beyond the limit" in figure_texts(figures[1])


def test_the_split_draws_the_joints_that_carry_torque_and_needs_drives(figures, tmp_path):
    ts, tp = _tables()
    ts["tau_j2_nm"] *= 0.1  # under 10 % of its limit with its drive terms: named, not drawn
    fl.follow_torque_split(ts, tp, LIMITS, "ground", "links+armature+coulomb+viscous", tmp_path / "a.png")
    fig = figures[0]
    assert fig._suptitle.get_text() == ("ground: the drives (rotor inertia, friction) take up to 30 % of joint 1's "
                                        "torque limit, the rest moves the links")
    assert [ax.get_title() for ax in fig.axes if ax.axison] == ["joint 1 (±10 N m): drives up to 30 %"]
    assert "not drawn: joint 3 unloaded, joint 2 below 10 % of its limit" in figure_texts(fig)
    assert {ax.get_xlabel() for ax in fig.axes if ax.get_xlabel()} == {"time t [s]"}  # as torques.png
    ts, tp = _tables("links")
    summary = {"command_duration_s": 11.0}
    fl.follow_torque_split(ts, tp, LIMITS, "space", "links", tmp_path / "b.png", summary)
    text = figure_texts(figures[1])
    assert "rotor" not in text and figures[1].texts == [figures[1]._suptitle]  # no footnote: the caption says why
    assert figures[1]._suptitle.get_text() == ("space, joint 1: TOPP-RA rides its torque limit 100 % of the time, "
                                               "the follower 25 %: it ramps up with its jerk-limited command")
    assert [ax.get_ylabel() for ax in figures[1].axes] == ["joint 1 torque [N m]"]  # the joint at its limit only


def test_an_infeasible_path_names_the_joint_and_its_need(figures, tmp_path):
    shortfall = {"output": "tau_j1_nm", "needed_nm": 1e6, "limit_nm": 10.0, "s_m": 0.0,
                 "what": "starting forward from rest (friction)"}
    fp.follow_infeasible("tau_j1_nm: starting forward from rest needs 1000000.00 N m", shortfall, LIMITS, "ground",
                         tmp_path / "i.png")
    text = figure_texts(figures[0])
    assert "joint 1 needs 100,000 × its limit" in text and "tau_j1_nm" not in text
    fp.follow_infeasible("no path from the start pose", None, LIMITS, "ground", tmp_path / "n.png")  # words only
    assert (tmp_path / "n.png").stat().st_size > 5_000
