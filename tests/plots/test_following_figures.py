"""The following figures tell their result from the data: the follower's duration against TOPP-RA's in the
progress figure's title, each joint's own limit (and its own periods at the limit) on its torque panel, no
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
    return "\n".join(out)


def _tables(terms: str = "links+armature+coulomb+viscous"):
    """A follower run of 12 s (joint 1 at its limit from 2 to 5 s, joint 3 unloaded) and TOPP-RA's of 10 s."""
    t = np.linspace(0.0, 12.0, 1201)
    s = 0.5 * (1 - np.cos(np.pi * t / 12.0))
    limited = (t >= 2.0) & (t <= 5.0)
    ts = pd.DataFrame({"case": "ground", "segment": (t > 6.0).astype(int), "t_s": t, "s_cmd_m": np.minimum(1.05 * s, 1.0),
                       "sd_cmd_mps": np.gradient(s, t), "s_m": s, "sd_mps": np.gradient(s, t), "lag_m": 0.01 * s * (1 - s),
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


def test_progress_puts_the_durations_in_the_title_and_writes_micrometres(figures, tmp_path):
    ts, tp = _tables()
    fp.follow_progress(ts, tp, "ground", tmp_path / "p.png")
    text = _texts(figures[0])
    assert "follower needs 12.0 s, 20 % more than TOPP-RA's time-optimal 10.0 s" in figures[0]._suptitle.get_text()
    assert "µm" in text and " um" not in text and "[um]" not in text


def test_each_torque_panel_shows_its_own_limit_and_its_own_periods_at_it(figures, tmp_path):
    ts, _ = _tables()
    fp.follow_torques(ts, LIMITS, "ground", tmp_path / "t.png")
    fig = figures[0]
    drawn = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title().split(" (")[0] for ax in drawn] == ["joint 1", "joint 2"]  # joint 3: no load, no panel
    for ax, lim in zip(drawn, (10.0, 100.0)):
        assert sorted(ln.get_ydata()[0] for ln in ax.lines if len(set(ln.get_ydata())) == 1) == [-lim, lim]
    assert len(drawn[0].collections) == 1 and len(drawn[1].collections) == 0  # only joint 1 is ever at its limit
    title = fig._suptitle.get_text()
    assert "keeps every torque limit (peak 100 % of joint 1's)" in title and "150 % of joint 1's" in title
    assert "joint 3: no load" in title


def test_the_split_needs_drives_else_the_figure_compares_with_toppra(figures, tmp_path):
    ts, tp = _tables()
    fp.follow_torque_split(ts, tp, LIMITS, "ground", "links+armature+coulomb+viscous", tmp_path / "a.png")
    assert "drives (rotor inertia, friction) take up to 30 % of joint 1's" in figures[0]._suptitle.get_text()
    ts, tp = _tables("links")
    fp.follow_torque_split(ts, tp, LIMITS, "space", "links", tmp_path / "b.png")
    text = _texts(figures[1])
    assert "no drive terms to split" in text and "rotor" not in text
    assert "TOPP-RA holds joint 1 at its limit 100 % of its time" in text
    assert [ax.get_title().split(" (")[0] for ax in figures[1].axes] == ["joint 1"]  # the joint at its limit only


def test_an_infeasible_path_names_the_joint_and_its_need(figures, tmp_path):
    shortfall = {"output": "tau_j1_nm", "needed_nm": 1e6, "limit_nm": 10.0, "s_m": 0.0,
                 "what": "starting forward from rest (friction)"}
    fp.follow_infeasible("tau_j1_nm: starting forward from rest needs 1000000.00 N m", shortfall, LIMITS, "ground",
                         tmp_path / "i.png")
    text = _texts(figures[0])
    assert "joint 1 needs 100,000 × its limit" in text and "tau_j1_nm" not in text
    fp.follow_infeasible("no path from the start pose", None, LIMITS, "ground", tmp_path / "n.png")  # words only
    assert (tmp_path / "n.png").stat().st_size > 5_000
