"""A dual-arm task that cannot be done is a result, not a failed job: a block where the right gripper must
hold the panel at its pre-insertion pose leaves that key pose no collision-free self-motion. The optimise
stage writes its tables (their columns, no rows), a summary with ``feasible`` False and the reason, and
the figures and the animation say so."""

from __future__ import annotations

import copy

import pandas as pd
import pytest
import yaml

from capmap.checks import check_run_config
from capmap.config.validation import load_yaml
from capmap.io import datasets
from capmap.stages.dualarm_figures import stage_dualarm_animation, stage_dualarm_plots
from tests.scenario import ROOT
from tests.stages.test_dualarm_chain import run_chain

# around the right gripper at the pre-insertion pose (panel centre (0.67, 0, 0.25), grasp 0.17 m to its right),
# clear of the panel's start pose (centre (0.50, 0.04, 0.05))
BLOCK = {"name": "block", "x_m": [0.60, 0.76], "y_m": [-0.26, -0.13], "z_m": [0.17, 0.33]}


@pytest.fixture(scope="module")
def blocked(tmp_path_factory):
    d = tmp_path_factory.mktemp("dualarm_blocked")
    scene = yaml.safe_load((ROOT / "config" / "scenes" / "satellite_panel.yaml").read_text())
    scene["boxes"].append(BLOCK)
    (d / "scene.yaml").write_text(yaml.safe_dump(scene))
    doc = copy.deepcopy(load_yaml(ROOT / "tests" / "data" / "tiny.yaml"))
    for key in ("follow", "reconfig"):
        doc.pop(key, None)
    doc["robot"] = str(ROOT / doc["robot"])
    doc["dualarm"]["robot"] = str(ROOT / doc["dualarm"]["robot"])
    doc["dualarm"]["scene"] = str(d / "scene.yaml")
    cfg = check_run_config(doc, "tiny.yaml")  # the block is only known to a job: the scan sees it
    return d, run_chain(cfg, d)


def test_a_key_pose_in_collision_is_written_as_infeasible(blocked):
    d, _ = blocked
    summary = dict(pd.read_csv(d / "s.csv").itertuples(index=False, name=None))
    assert summary["feasible"] in (False, "False")
    assert "pose is not collision-free" in summary["reason"] and "pre-insertion pose" in summary["reason"]
    traj = datasets.read(d / "traj.parquet")
    assert traj.empty and "q_right_s0_rad" in traj.columns and "min_distance_m" in traj.columns
    assert traj.attrs["capmap"]["feasible"] is False
    assert datasets.read(d / "torques.parquet").empty and datasets.read(d / "outer.parquet").empty


def test_its_figures_and_animation_say_why(blocked):
    d, sl = blocked
    names = ("errors", "distances", "joints", "velocities", "torques", "convergence")
    stage_dualarm_plots(str(d / "traj.parquet"), str(d / "fine.parquet"), str(d / "outer.parquet"),
                        str(d / "torques.parquet"), {n: str(d / f"{n}.png") for n in names})
    assert all((d / f"{n}.png").stat().st_size > 10_000 for n in names)
    stage_dualarm_animation(str(d / "traj.parquet"), str(d / "env.parquet"), str(d / "capsules.parquet"),
                            str(d / "a.html"), sl("dualarm_animation"))
    assert "no motion:" in (d / "a.html").read_text()
