"""`snakemake advise` and `capmap advise` on the tiny config: the advice's outputs hold together (the
recommendation is the best swept angle of its own task table, the failure-tolerant map is the least of the
joints' sweeps), a change of the angle step reruns only the advice, and a bad joint is one line."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from capmap.io.datasets import verify_catalogue
from tests.scenario import ROOT
from tests.workflow.runs import config_file, planned_jobs_of

pytestmark = pytest.mark.slow  # a tiny advice: .ci/run runs these (-m slow)


def test_advise_target_recommends_the_best_swept_angle(tmp_path):
    cfg = config_file(tmp_path, **{"advice": {"step_deg": 60}})
    res = subprocess.run(["snakemake", "advise", "-s", str(ROOT / "Snakefile"), "-d", str(tmp_path), "--cores", "2",
                          "--configfile", str(cfg)], capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    out = tmp_path / "results/tiny/advice"
    tasks = pd.read_parquet(out / "joint1/tasks.parquet")
    assert tasks.angle_deg.nunique() == 6 and set(tasks.task) == {"task"} and len(tasks) == 6
    assert np.isclose(tasks.angle_deg, 100.0).any()  # the sweep passes through the lock angle
    advice = pd.read_parquet(out / "joint1/advice.parquet").iloc[0]
    worst = tasks.groupby("angle_deg").margin_pct.min()
    assert advice.worst_margin_pct == worst.max() and worst[advice.recommended_angle_deg] == worst.max()
    assert advice.stands_at_deg == 100.0 and advice.n_angles == 6
    sweeps = pd.concat([pd.read_parquet(out / f"sweeps/joint{j}.parquet") for j in range(1, 8)])
    tol = pd.read_parquet(out / "tolerant.parquet")
    for r in tol.sample(min(len(tol), 25), random_state=0).itertuples():  # by hand: every lock reaching the voxel
        mine = sweeps[(sweeps.i == r.i) & (sweeps.j == r.j) & (sweeps.k == r.k)]
        assert len(mine) == 7 * 6 and mine.joint.nunique() == 7
        whole = [c if n == p else np.nan for c, n, p in zip(mine.capacity_kg, mine.n_reachable, mine.n_points)]
        assert (np.isnan(r.tolerant_capacity_kg) if np.isnan(whole).any() else r.tolerant_capacity_kg == min(whole))
    # the run's own plan at the run's lock angle: the advice there carries at least what it carries
    plan = pd.read_parquet(tmp_path / "results/tiny/plan/payload_1500kg/waypoints.parquet")
    here = tasks[np.isclose(tasks.angle_deg, 100.0)].iloc[0]
    assert (np.isnan(here.run_plan_capacity_kg) if not len(plan) else here.capacity_kg >= here.run_plan_capacity_kg)
    cat = pd.read_parquet(out / "catalogue.parquet")
    assert len(cat) == 7 + 4 + 2 and cat.name.is_unique
    assert verify_catalogue(out / "catalogue.parquet", tmp_path) == []  # what `capmap check` runs on it
    # a finer step reruns the sweeps and the advice, nothing of the main map
    cfg2 = config_file(tmp_path, **{"advice": {"step_deg": 45}})
    assert planned_jobs_of(tmp_path, cfg2, "advise") == {"lock_sweep": 7, "advice_tasks": 1, "advice_joint": 1,
                                                         "tolerant": 1, "advice_catalogue": 1, "advise": 1}
    # another joint through the command: its sweep is already there, only its tasks and advice run
    res = subprocess.run([sys.executable, "-m", "capmap", "advise", str(cfg), "--joint", "4"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    assert res.stdout.splitlines()[-1].startswith("joint 4: brake it at ") and "lock_sweep" not in res.stderr
    bad = subprocess.run([sys.executable, "-m", "capmap", "advise", str(cfg), "--joint", "8"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode == 1 and bad.stderr.strip().splitlines() == [
        "capmap: advise: --joint 8 is not a joint: the arm has joints 1..7"]
