"""The following and reconfiguration stages called as their rules call them (slices from
capmap.config.slices, no Snakemake) on the tiny config's cases, each output held against physics the
test states itself: the follower never beats TOPP-RA's time-optimal duration on the same path and
limits, ends at the path's end at rest and keeps every joint torque within its limit (to the control
period's rounding); the reconfiguration drives the passive joint along the law to its target."""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest

from capmap.checks import check_run_config
from capmap.config import canonical, stage_slice
from capmap.config.validation import load_yaml
from capmap.core.reduction import free
from capmap.io import datasets
from capmap.stages.following import stage_follow
from capmap.stages.following_figures import stage_follow_plots
from capmap.stages.reconfig import stage_reconfig, stage_reconfig_summary
from capmap.stages.reconfig_figures import stage_reconfig_animation, stage_reconfig_plots
from tests.scenario import ROOT


@pytest.fixture(scope="module")
def cfg():
    doc = copy.deepcopy(load_yaml(ROOT / "tests" / "data" / "tiny.yaml"))
    doc.pop("dualarm", None)
    doc["robot"] = str(ROOT / doc["robot"])
    doc["follow"]["ground"]["robot"] = str(ROOT / doc["follow"]["ground"]["robot"])
    doc["reconfig"]["robot"] = str(ROOT / doc["reconfig"]["robot"])
    return check_run_config(doc, "tiny.yaml")


def test_follow_ground_stage_is_never_faster_than_toppra_and_keeps_its_limits(cfg, tmp_path):
    d = tmp_path
    stage_follow("ground", str(d / "ts.parquet"), str(d / "tp.parquet"), str(d / "s.csv"), str(d / "s.md"),
                 canonical(stage_slice(cfg, "follow_ground")))
    ts, row = datasets.read(d / "ts.parquet"), pd.read_csv(d / "s.csv").iloc[0]
    g = cfg.follow.ground
    assert row.follower_duration_s >= row.toppra_duration_s * (1 - 1e-9)  # TOPP-RA is time-optimal
    assert ts.s_m.iloc[-1] == pytest.approx(np.linalg.norm(g.line_m), abs=1e-4) and abs(ts.sd_mps.iloc[-1]) < 1e-3
    tau = ts[[f"tau_j{j}_nm" for j in range(1, 7)]].abs().to_numpy()
    # a limit held at each control instant, to the period's rounding (the state moves within a period)
    assert np.all(tau <= np.asarray(g.joint_torque_nm) * (1 + 1e-3))
    stage_follow_plots(str(d / "ts.parquet"), str(d / "tp.parquet"),
                       dict(s=str(d / "p.png"), torques=str(d / "t.png"), split=str(d / "split.png")), "{}")
    assert all((d / n).stat().st_size > 10_000 for n in ("p.png", "t.png", "split.png"))
    # a path not followed from its first segment keeps these tables' columns
    from capmap.following.tables import PathRun, follow_tables
    from capmap.robots import load

    empty = follow_tables("ground", free(load(g.robot)), PathRun([], [], None, "links"))
    assert [list(t.columns) for t in empty] == [list(ts.columns), list(datasets.read(d / "tp.parquet").columns)]


def test_reconfig_stages_follow_the_law_to_its_target(cfg, tmp_path):
    d, rc = tmp_path, cfg.reconfig
    tables, timings, completed = [], [], 0
    for method, stage in (("pinv", "reconfig_pinv"), ("nullspace", "reconfig_nullspace")):
        stage_reconfig(method, str(d / f"{method}.parquet"), str(d / f"{method}.json"),
                       canonical(stage_slice(cfg, stage)))
        tables.append(str(d / f"{method}.parquet"))
        timings.append(str(d / f"{method}.json"))
        df = datasets.read(d / f"{method}.parquet")
        if df.attrs["capmap"]["status"] == "completed":  # the passive joint reaches the law's end values
            completed += 1
            assert df.passive_theta_deg.iloc[-1] == pytest.approx(rc.theta_deg, abs=1e-6)
            assert df.passive_d_m.iloc[-1] == pytest.approx(rc.d_m, abs=1e-9)
        assert json.loads((d / f"{method}.json").read_text())  # its timing
    assert completed >= 1  # the tiny law is within reach of at least one method
    stage_reconfig_summary(tables, timings, str(d / "s.csv"), str(d / "s.md"))
    assert set(pd.read_csv(d / "s.csv").method) == {"pinv", "nullspace"}
    stage_reconfig_plots(tables, dict(manipulability=str(d / "m.png"), rates=str(d / "r.png"), passive=str(d / "p.png")))
    assert all((d / n).stat().st_size > 10_000 for n in ("m.png", "r.png", "p.png"))
    stage_reconfig_animation(tables, str(d / "a.html"), canonical(stage_slice(cfg, "reconfig_animation")))
    assert (d / "a.html").stat().st_size > 10_000


def _ground_robot_with(tmp_path, coulomb_nm: float):
    """The default ground robot (UR5 on drives) with the shoulder pan's Coulomb friction set."""
    import yaml

    doc = yaml.safe_load((ROOT / "config" / "robots" / "ur5_drives.yaml").read_text())
    doc["drives"]["shoulder_pan_joint"]["friction"]["coulomb_nm"] = coulomb_nm
    path = tmp_path / "ur5_stuck.yaml"
    path.write_text(yaml.safe_dump(doc))
    return str(path)


def test_follow_stage_writes_a_path_it_cannot_start_as_infeasible(tmp_path):
    """Coulomb friction above the joint's limit: the arm cannot start forward from rest. A result, not an
    error: the job's tables are written (no time series rows), the summary says why, each figure shows it."""
    doc = copy.deepcopy(load_yaml(ROOT / "tests" / "data" / "tiny.yaml"))
    doc.pop("dualarm", None)
    doc["robot"] = str(ROOT / doc["robot"])
    doc["reconfig"]["robot"] = str(ROOT / doc["reconfig"]["robot"])
    doc["follow"]["ground"]["robot"] = _ground_robot_with(tmp_path, 1e6)
    run = check_run_config(doc, "tiny.yaml")  # a finite friction: not a bad input
    d = tmp_path
    stage_follow("ground", str(d / "ts.parquet"), str(d / "tp.parquet"), str(d / "s.csv"), str(d / "s.md"),
                 canonical(stage_slice(run, "follow_ground")))
    row = pd.read_csv(d / "s.csv").iloc[0]
    limit = run.follow.ground.joint_torque_nm[0]
    assert not row.feasible and "tau_j1_nm" in row.reason and "1000000.00 N m" in row.reason
    assert np.isnan(row.follower_duration_s)
    ts = datasets.read(d / "ts.parquet")
    assert len(ts) == 0 and "tau_j1_nm" in ts.columns and len(datasets.read(d / "tp.parquet")) == 0
    meta = ts.attrs["capmap"]
    assert meta["shortfall"]["needed_nm"] == pytest.approx(1e6, rel=1e-3)  # Coulomb alone, against the motion
    assert meta["shortfall"]["limit_nm"] == pytest.approx(limit)
    out = {k: str(d / f"{k}.png") for k in ("s", "torques", "split")}
    stage_follow_plots(str(d / "ts.parquet"), str(d / "tp.parquet"), out, "{}")
    assert all((d / f"{k}.png").stat().st_size > 10_000 for k in out)
    if "CAPMAP_KEEP_FIGURES" in __import__("os").environ:
        __import__("shutil").copy(d / "torques.png", __import__("os").environ["CAPMAP_KEEP_FIGURES"])
