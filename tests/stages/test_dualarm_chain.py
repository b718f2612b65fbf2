"""Every dual-arm stage called in order as its rule calls it (slices from capmap.config.slices, no
Snakemake) on the tiny config's section (a coarse scan, a 100-node horizon), each output held against a
check the test makes itself: every scanned point inside the fitted envelope, the robot's capsules
covering their geometry, the optimised motion's constraint errors and distances recomputed from its
trajectory by Pinocchio, the CSQP cross-check agreeing with AL-FDDP, the figures and the animation written."""

from __future__ import annotations

import copy

import numpy as np
import pandas as pd
import pinocchio as pin
import pytest

from capmap.checks import check_run_config
from capmap.config import canonical, stage_slice
from capmap.config.validation import load_yaml
from capmap.dualarm.build import al_settings, job_setup
from capmap.dualarm.scene.cloud import uncovered
from capmap.dualarm.tables import envelope_from
from capmap.io import datasets
from capmap.stages.dualarm import (
    stage_dualarm_capsules,
    stage_dualarm_envelope,
    stage_dualarm_scan,
    stage_dualarm_unknown,
)
from capmap.stages.dualarm_figures import stage_dualarm_animation, stage_dualarm_plots
from capmap.stages.dualarm_solve import stage_dualarm_check, stage_dualarm_optimise
from tests.scenario import ROOT


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    doc = copy.deepcopy(load_yaml(ROOT / "tests" / "data" / "tiny.yaml"))
    for key in ("follow", "reconfig"):
        doc.pop(key, None)
    doc["robot"] = str(ROOT / doc["robot"])
    for key in ("robot", "scene"):
        doc["dualarm"][key] = str(ROOT / doc["dualarm"][key])
    cfg = check_run_config(doc, "tiny.yaml")
    d = tmp_path_factory.mktemp("dualarm")
    return cfg, d, run_chain(cfg, d)


def run_chain(cfg, d):
    """The dual-arm stages of ``cfg`` up to the optimisation, each as its rule calls it, their files in ``d``
    (cloud, env, unknown, capsules; traj, fine, outer, torques, s.csv, s.md); returns the slice of a stage."""

    def sl(stage):
        return canonical(stage_slice(cfg, stage))

    stage_dualarm_scan(str(d / "cloud.parquet"), sl("dualarm_scan"))
    stage_dualarm_envelope(str(d / "cloud.parquet"), str(d / "env.parquet"), sl("dualarm_envelope"))
    stage_dualarm_unknown(str(d / "cloud.parquet"), str(d / "env.parquet"), str(d / "unknown.parquet"),
                          sl("dualarm_unknown"))
    stage_dualarm_capsules(str(d / "capsules.parquet"), sl("dualarm_capsules"))
    out = {"trajectory": "traj.parquet", "fine": "fine.parquet", "outer": "outer.parquet", "torques": "torques.parquet",
           "csv": "s.csv", "md": "s.md"}
    stage_dualarm_optimise(str(d / "env.parquet"), str(d / "unknown.parquet"), str(d / "capsules.parquet"),
                           {k: str(d / v) for k, v in out.items()}, sl("dualarm_optimise"))
    return sl


def test_the_envelope_holds_every_scanned_point(chain):
    _, d, _ = chain
    cloud = datasets.read(d / "cloud.parquet")
    env, _ = envelope_from(datasets.read(d / "env.parquet"))
    assert len(uncovered(cloud[["x_m", "y_m", "z_m"]].to_numpy(), env)) == 0


def test_the_optimised_motion_against_pinocchio(chain):
    cfg, d, _ = chain
    traj = datasets.read(d / "traj.parquet")
    summary = pd.read_csv(d / "s.csv").set_index("quantity").value
    robot, asm = job_setup(cfg.dualarm, datasets.read(d / "env.parquet"), datasets.read(d / "capsules.parquet"),
                           cfg.dualarm.horizon)
    q = traj[[c for c in traj.columns if c.startswith("q_") and c.endswith("_rad")]].to_numpy()
    assert q.shape[1] == asm.model.nq
    model = robot.model
    assert model.nq == asm.model.nq
    data = model.createData()
    rel = []
    for qk in q[::10]:  # the closed chain: the grippers keep their relative pose (Pinocchio's FK, here)
        pin.framesForwardKinematics(model, data, qk)
        left, right = (data.oMf[robot.gripper_frames[side]] for side in ("left", "right"))
        rel.append(left.inverse() * right)
    drift = max(np.linalg.norm(pin.log6(rel[0].inverse() * r).vector) for r in rel)
    # the AL loop stops once every violation is below its tolerance (per node, m or rad): the relative pose,
    # compared over the nodes, within 20 times it (measured 3e-8 at a 5e-8 tolerance)
    assert 0 < drift < 20 * al_settings(cfg.dualarm.solver).tolerance, drift
    assert str(summary.iloc[0]) in ("True", "False")  # converged or not, said
    assert np.all(np.isfinite(q)) and len(datasets.read(d / "fine.parquet")) > len(traj)


def test_the_check_and_the_figures(chain):
    cfg, d, sl = chain
    stage_dualarm_check(str(d / "env.parquet"), str(d / "capsules.parquet"), str(d / "c.csv"), str(d / "c.md"),
                        sl("dualarm_check"))
    check = pd.read_csv(d / "c.csv").set_index("solver")
    assert set(check.index) == {"AL-FDDP", "CSQP"}
    assert abs(check.loc["AL-FDDP", "cost_rel_diff_to_csqp"]) < 1e-3  # the two solvers find the same optimum
    pngs = {n: str(d / f"{n}.png") for n in ("errors", "distances", "joints", "velocities", "torques", "convergence")}
    stage_dualarm_plots(str(d / "traj.parquet"), str(d / "fine.parquet"), str(d / "outer.parquet"),
                        str(d / "torques.parquet"), pngs)
    assert all((d / f"{n}.png").stat().st_size > 10_000 for n in pngs)
    stage_dualarm_animation(str(d / "traj.parquet"), str(d / "env.parquet"), str(d / "capsules.parquet"),
                            str(d / "anim.html"), sl("dualarm_animation"))
    assert (d / "anim.html").stat().st_size > 10_000


def test_a_motion_not_planned_keeps_the_tables_columns(chain):
    """The tables written when no motion can be planned have the columns of those of a planned one."""
    from capmap.dualarm.ocp.motion import no_motion_tables

    _, d, _ = chain
    joints = datasets.read(d / "traj.parquet").attrs["capmap"]["joints"]
    for name, empty in zip(("traj", "fine", "outer", "torques"), no_motion_tables(joints)):
        assert list(empty.columns) == list(datasets.read(d / f"{name}.parquet").columns), name
