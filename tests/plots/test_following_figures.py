"""The following figures tell their result from the data: the follower's gap to TOPP-RA split into its
command's part and the torque limits' part (the same in the progress and the split figure), the binding joint
on its own limit and the others in % of theirs, where the limits come from, the follower's stops marked, no
panel for a joint the path does not load, a drive split only for a robot with drives, and a readable figure
for a path that cannot be followed. Synthetic tables; the figures' texts read from the figure objects."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import capmap.plots.following as fp
from capmap.plots.common import plt

LIMITS = {"tau_j1_nm": 10.0, "tau_j2_nm": 100.0, "tau_j3_nm": 50.0}


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions would save, kept open for reading."""
    kept = []
    monkeypatch.setattr(fp, "save", lambda fig, out_png, rect=None: kept.append(fig))
    yield kept
    for fig in kept:
        plt.close(fig)


def _texts(fig) -> str:
    out = [fig._suptitle.get_text() if fig._suptitle else ""]
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_ylabel(), ax.get_xlabel()] + [t.get_text() for t in ax.texts]
        if ax.get_legend():
            out += [t.get_text() for t in ax.get_legend().get_texts()]
    for leg in fig.legends:
        out += [t.get_text() for t in leg.get_texts()]
    return "\n".join(out + [t.get_text() for t in fig.texts])


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


def test_progress_splits_the_gap_to_toppra_into_the_command_and_the_torque_limits(figures, tmp_path):
    ts, tp = _tables()
    _config(ts, follow={"ground": {"v_max_mps": 0.2, "joint_torque_nm": [10, 100, 50]}})
    fp.follow_progress(ts, tp, LIMITS, "ground", tmp_path / "p.png", {"command_duration_s": 11.0})
    title, text = figures[0]._suptitle.get_text(), _texts(figures[0])
    assert "the follower takes 20 % longer than TOPP-RA" in title
    assert "+1.00 s from its jerk-limited command, +1.00 s from the torque limits" in title
    assert "S-curve command, jerk-limited (11.00 s): ignores the torque limits\n(needs 150 % of joint 1's)" in text
    assert "speed limit 0.2 m/s (follow.ground.v_max_mps)" in text  # the limit both speeds plateau at, drawn
    assert any(ln.get_ydata()[0] == 0.2 and len(set(ln.get_ydata())) == 1 for ln in figures[0].axes[1].lines)
    assert "within 0.001 µm" in text and " um" not in text and "[um]" not in text  # the deviation: a line of text
    assert len(figures[0].axes) == 3


def test_progress_says_when_toppra_exceeds_a_limit_under_the_full_model(figures, tmp_path):
    ts, tp = _tables()
    tp["tau_j1_nm"] *= 1.2  # TOPP-RA's torques measured with a term its own model lacks
    fp.follow_progress(ts, tp, LIMITS, "ground", tmp_path / "p.png",
                       {"follower_terms": "links+armature+coulomb+viscous", "toppra_terms": "links+armature+coulomb"})
    assert "its model lacks viscous friction; with the full model it needs 120 % of joint 1's limit" in _texts(figures[0])
    fp.follow_progress(ts, tp, LIMITS, "ground", tmp_path / "q.png")  # no summary row: the command's time from the rows
    assert "from its jerk-limited command" in figures[1]._suptitle.get_text()


def test_torques_draw_the_binding_joint_on_its_own_limit_and_the_rest_in_percent(figures, tmp_path):
    ts, _ = _tables()
    _config(ts, follow={"space": {"joint_torque_nm": 100}}, limits={"joint_torque_nm": 700},
            failure={"joint": 7, "angle_deg": 100})
    fp.follow_torques(ts, LIMITS, "space", tmp_path / "t.png")
    fig = figures[0]
    joint1, rest = fig.axes[0], fig.axes[1]
    assert joint1.get_title().startswith("joint 1 (±10 N m)") and len(joint1.collections) == 1  # at its limit: shaded
    flat = lambda ax: sorted(ln.get_ydata()[0] for ln in ax.lines if len(set(ln.get_ydata())) == 1)  # noqa: E731
    assert flat(joint1) == [-10.0, 10.0] and flat(rest) == [-100.0, 100.0]  # its limit; the others' in %
    assert "the other joints, each in % of its own limit: follower peaks joint 2 30 %" in rest.get_title()
    assert rest.get_ylabel() == "torque [% of the joint's limit]" and len(rest.collections) == 0
    title = fig._suptitle.get_text()
    assert "keeps every torque limit (peak 100 % of joint 1's)" in title and "150 % of joint 1's (15 N m)" in title
    assert "limits: config follow.space.joint_torque_nm = 100 N m, tighter than" in title and "= 700 N m" in title
    assert "not drawn: joint 7 (locked at 100°), joint 3 (no load on this path)" in title


def test_the_followers_stops_at_the_waypoints_are_marked_and_explained(figures, tmp_path):
    ts, _ = _tables()
    k = int(np.flatnonzero(ts.segment.to_numpy() == 0)[-1]) - 3  # segment 1 ends in a crawl braked in one period
    ts.loc[k - 5:k, "sd_mps"], ts.loc[k + 1:k + 3, "sd_mps"] = 1e-6, 0.0
    ts.loc[k - 5:k, "sdd_mps2"], ts.loc[k, "sdd_mps2"] = 1e-5, -1e-3
    ts.loc[k, "tau_j1_nm"] = -9.0  # its torque pulse
    fp.follow_torques(ts, LIMITS, "ground", tmp_path / "t.png")
    marks = [ln for ln in figures[0].axes[0].lines if ln.get_marker() == "o"]
    assert len(marks) == 1 and marks[0].get_ydata()[0] == -9.0
    assert "the follower's stop at a waypoint: its last ≤ 0.001 mm/s braked within ≤ 1 ms" in _texts(figures[0])


def test_the_split_needs_drives_else_the_figure_compares_with_toppra(figures, tmp_path):
    ts, tp = _tables()
    fp.follow_torque_split(ts, tp, LIMITS, "ground", "links+armature+coulomb+viscous", tmp_path / "a.png")
    assert "drives (rotor inertia, friction) take up to 30 % of joint 1's" in figures[0]._suptitle.get_text()
    assert {ax.get_xlabel() for ax in figures[0].axes if ax.get_xlabel()} == {"time t [s]"}  # as torques.png
    ts, tp = _tables("links")
    summary = {"command_duration_s": 11.0}
    fp.follow_torque_split(ts, tp, LIMITS, "space", "links", tmp_path / "b.png", summary)
    fp.follow_progress(ts, tp, LIMITS, "space", tmp_path / "p.png", summary)
    text = _texts(figures[1])
    assert "nothing to split" in text and "rotor" not in text
    assert "TOPP-RA rides the torque limit" in figures[1]._suptitle.get_text()
    assert "at the limit 100 % of its time" in text  # TOPP-RA's joint 1
    assert [ax.get_ylabel() for ax in figures[1].axes] == ["joint 1 torque [N m]"]  # the joint at its limit only
    # the same cause as the progress figure's: the command's part and the torque limits' part of the gap
    assert "its command's jerk limit takes +1.00 s, the torque limit +1.00 s" in text
    assert "+1.00 s from its jerk-limited command, +1.00 s from the torque limits" in figures[2]._suptitle.get_text()


def test_an_infeasible_path_names_the_joint_and_its_need(figures, tmp_path):
    shortfall = {"output": "tau_j1_nm", "needed_nm": 1e6, "limit_nm": 10.0, "s_m": 0.0,
                 "what": "starting forward from rest (friction)"}
    fp.follow_infeasible("tau_j1_nm: starting forward from rest needs 1000000.00 N m", shortfall, LIMITS, "ground",
                         tmp_path / "i.png")
    text = _texts(figures[0])
    assert "joint 1 needs 100,000 × its limit" in text and "tau_j1_nm" not in text
    fp.follow_infeasible("no path from the start pose", None, LIMITS, "ground", tmp_path / "n.png")  # words only
    assert (tmp_path / "n.png").stat().st_size > 5_000
