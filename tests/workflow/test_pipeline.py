"""The Snakemake pipeline on the tiny config: outputs, provenance, catalogue, exact caching."""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pandas as pd
import pytest

from tests.scenario import ROOT, X_DES, X_INI
from tests.workflow.runs import config_file, planned_jobs, planned_jobs_of, snakemake_run

pytestmark = pytest.mark.slow  # a whole tiny pipeline: .ci/run runs these (-m slow)


def test_outputs_and_provenance(run_dir):
    tmp, _ = run_dir
    pts = pd.read_parquet(tmp / "results/tiny/capacity/points.parquet")
    vox = pd.read_parquet(tmp / "results/tiny/voxels/voxels.parquet")
    for col in ("point_id", "x_m", "y_m", "z_m", "reachable", "n_branches", "capacity_kg", "binding",
                "worst_alpha_deg", "worst_beta_deg", "worst_branch"):
        assert col in pts.columns
    for col in ("i", "j", "k", "x_m", "y_m", "z_m", "n_points", "capacity_kg"):
        assert col in vox.columns
    meta = pts.attrs["capmap"]
    assert meta["stage"] == "capacity" and meta["seed"] == 7 and meta["capmap_version"]
    assert meta["config"]["run"]["limits"]["joint_torque_nm"] == 700
    # points: each id exactly once across shards
    assert pts.point_id.is_unique and np.array_equal(pts.point_id, np.arange(len(pts)))  # every sampled point once
    # reachable <=> at least one branch <=> finite capacity
    assert np.array_equal(pts.reachable, pts.n_branches > 0)
    assert np.array_equal(pts.reachable, np.isfinite(pts.capacity_kg))
    assert pts.reachable.sum() > 20


def test_voxel_capacity_is_min_of_points_inside(run_dir):
    tmp, _ = run_dir
    pts = pd.read_parquet(tmp / "results/tiny/capacity/points.parquet")
    vox = pd.read_parquet(tmp / "results/tiny/voxels/voxels.parquet")
    grid = vox.attrs["capmap"]["grid"]
    edge, lower = grid["edge_m"], np.array(grid["lower_m"])
    # independent binning
    idx = np.floor((pts[["x_m", "y_m", "z_m"]].to_numpy() - lower) / edge).astype(int)
    pts = pts.assign(ii=idx[:, 0], jj=idx[:, 1], kk=idx[:, 2])
    expect = pts[pts.reachable].groupby(["ii", "jj", "kk"]).capacity_kg.min()
    got = vox[vox.n_reachable > 0].set_index(["i", "j", "k"]).capacity_kg
    got.index.names = expect.index.names
    pd.testing.assert_series_equal(got.sort_index(), expect.sort_index(), check_names=False)
    assert vox[vox.n_reachable == 0].capacity_kg.isna().all()
    # centres = lower + (index + 1/2) edge, lower corner on multiples of the edge
    assert np.allclose(vox.x_m, lower[0] + (vox.i + 0.5) * edge)
    assert np.allclose(lower / edge, np.round(lower / edge))
    # voxel_fill evaluated every voxel of the grid
    assert (vox.n_points > 0).all()


def test_catalogue_lists_every_dataset(run_dir):
    tmp, _ = run_dir
    cat = pd.read_parquet(tmp / "results/tiny/catalogue.parquet")
    assert set(cat.name) == {"joints", "points", "voxels", "configurations", "plan_1500kg",
                             "verify_1500kg", "verify_1500kg_segments", "follow_space", "follow_space_toppra",
                             "follow_ground", "follow_ground_toppra", "reconfig_nullspace", "reconfig_pinv",
                             "dualarm_cloud", "dualarm_environment", "dualarm_unknown", "dualarm_capsules",
                             "dualarm_trajectory", "dualarm_fine", "dualarm_solver", "dualarm_torques"}
    assert len(cat) == 21 and cat.name.is_unique and (cat.description.str.len() > 40).all()
    # the per-shard tables and the sample were temporary: gone once merged, only the merged tables remain
    assert not list((tmp / "results/tiny").glob("**/*_of_*.parquet"))
    assert not (tmp / "results/tiny/sample/points.parquet").exists()
    assert not (tmp / "results/tiny/voxels/sampled.parquet").exists()
    for row in cat.itertuples():  # every column name is a Python identifier (DataFrame.query, attribute access)
        assert all(c.split(" [")[0].isidentifier() for c in row.columns), row.path
    for _, row in cat.iterrows():
        data = (tmp / row.path).read_bytes()
        assert hashlib.sha256(data).hexdigest() == row.sha256
        assert row.rows == len(pd.read_parquet(tmp / row.path))
        assert row.config_hash
    cols = cat.set_index("path").loc["results/tiny/voxels/voxels.parquet", "columns"]
    assert "capacity_kg [kg]" in list(cols) and "x_m [m]" in list(cols)


def test_caching_reruns_exactly_the_affected_stages(run_dir, tmp_path):
    tmp, cfg = run_dir
    assert planned_jobs(tmp, cfg) == {}
    changes = [
        {"limits.joint_torque_nm": 650},
        {"limits.base_moment_nm": 450},
        {"lock.angle_deg": 95},
        {"lock.joint": 7},
        {"lock.angle_deg": None},
        {"task.payload_kg": 900, "follow.space.payload_kg": 900},
        {"task.payload_kg": [1500, 900]},
        {"verification.dt_s": 0.2},
        {"task.q_ini_deg": [100, 124.5, 98, 130, 146, 174, 57]},
        {"follow.ground.joint_torque_nm": 15},
        {"follow.period_s": 0.002},
        {"task.v_max_mps": 0.1},
        {"reconfig.kappa0": 0.0003},
        {"reconfig.animation_fps": 4},
        {"reconfig.law.d_m": 0.2},
        {"dualarm.weights.velocity": 2.0},
        {"dualarm.margin_m": 0.004},
        {"dualarm.check.max_iterations": 50},
        {"dualarm.animation_fps": 4},
        {"dualarm.cloud.noise_m": 0.004},
    ]
    with ThreadPoolExecutor(2) as pool:  # dry runs in parallel (each parses the workflow: seconds)
        run = list(pool.map(lambda ch: planned_jobs(tmp, config_file(tmp_path, **ch)), changes))
    # a plan also redraws the 3D map; every summary the report's table pages
    after_payload = {"plan", "capacity_3d", "verify", "verify_plots", "verify_summary", "catalogue", "report_tables", "all"}
    follow = {"follow", "follow_plots", "follow_summary"}
    gain = set()  # the plan-gain experiment is not in all (target experiments)
    # the sample is temporary (rebuilt in a tenth of a second when the capacity shards need it again)
    downstream_of_capacity = {"sample", "capacity", "points", "voxels", "voxel_map", "summary"} | gain | after_payload | follow
    jobs = run[0]
    assert set(jobs) == downstream_of_capacity and jobs["capacity"] == 2
    jobs = run[1]
    assert set(jobs) == downstream_of_capacity
    # the failure in one edit: another angle, or another joint locked where it stood
    jobs = run[2]
    assert set(jobs) == {"sample"} | downstream_of_capacity
    jobs = run[3]
    assert set(jobs) == {"sample"} | downstream_of_capacity
    # the lock angle written out as it stood, or the start written out as FK(q_ini): the same run
    assert run[4] == {}
    jobs = run[5]
    # the space case follows the new plan; the map's figure draws the payloads' contours
    assert set(jobs) == after_payload | gain | follow | {"summary"} and jobs["follow"] == 1
    # a second payload: one new plan/verify/plots job each, nothing for the first payload (nor its follower)
    jobs = run[6]
    assert set(jobs) == after_payload | gain | {"summary"} and jobs["plan"] == jobs["verify"] == jobs["verify_plots"] == 1
    jobs = run[7]
    # the follower does not sample at dt_s; the map's figure and 3D page show the verified verdicts
    assert set(jobs) == (after_payload - {"plan"}) | gain | {"summary"}
    # q_ini matters through the start branch it selects: rounded differently, nothing reruns
    assert run[8] == {}
    # the follower's own settings: only that case
    jobs = run[9]
    assert set(jobs) == follow | {"catalogue", "report_tables", "all"} and jobs["follow"] == jobs["follow_plots"] == 1
    jobs = run[10]
    assert set(jobs) == follow | {"catalogue", "report_tables", "all"} and jobs["follow"] == 2
    jobs = run[11]
    assert set(jobs) == downstream_of_capacity
    # the reconfiguration family: kappa0 is the null-space method's only; the frame rate the animation's
    reconfig = {"reconfig", "reconfig_summary", "reconfig_plots", "reconfig_animation", "catalogue", "report_tables", "all"}
    jobs = run[12]
    assert set(jobs) == reconfig and jobs["reconfig"] == 1
    jobs = run[13]
    assert set(jobs) == {"reconfig_animation", "all"}
    jobs = run[14]
    assert set(jobs) == reconfig and jobs["reconfig"] == 2
    # the dual-arm family: a cost weight re-optimises, the scene and the capsules stay
    motion = {"dualarm_optimise", "dualarm_check", "dualarm_plots", "dualarm_animation", "catalogue", "report_tables", "all"}
    jobs = run[15]
    assert set(jobs) == motion
    jobs = run[16]
    assert set(jobs) == motion - {"dualarm_check"}  # the check has no inequalities
    jobs = run[17]
    assert set(jobs) == {"dualarm_check", "report_tables", "all"}
    jobs = run[18]
    assert set(jobs) == {"dualarm_animation", "all"}
    jobs = run[19]
    assert set(jobs) == {"dualarm_scan", "dualarm_envelope", "dualarm_unknown"} | motion


def test_changing_shard_count_recomputes_consistently(run_dir, tmp_path):
    tmp, _ = run_dir
    cfg3 = config_file(tmp_path, shards=3)
    jobs = planned_jobs(tmp, cfg3)
    assert jobs.get("capacity") == 3 and jobs.get("sample") == 1 and "model" not in jobs  # the sample: temporary
    before = pd.read_parquet(tmp / "results/tiny/voxels/voxels.parquet")
    work3 = tmp_path / "w3"
    work3.mkdir()
    res = snakemake_run(work3, cfg3)
    assert res.returncode == 0, res.stderr[-2000:]
    after = pd.read_parquet(work3 / "results/tiny/voxels/voxels.parquet")
    pd.testing.assert_series_equal(before.capacity_kg, after.capacity_kg)


def test_plan_and_verify_outputs(run_dir):
    tmp, _ = run_dir
    res = tmp / "results" / "tiny"
    wp = pd.read_parquet(res / "plan/payload_1500kg/waypoints.parquet")
    meta = wp.attrs["capmap"]
    assert meta["status"] == "ok" and meta["payload_kg"] == 1500
    assert meta["config"]["job"]["payload_kg"] == 1500
    assert np.allclose(wp[["x_m", "y_m", "z_m"]].iloc[0], X_INI) and np.allclose(wp[["x_m", "y_m", "z_m"]].iloc[-1], X_DES)
    assert (wp.voxel_capacity_kg >= 1500).all()
    ts = pd.read_parquet(res / "verify/payload_1500kg/timeseries.parquet")
    seg = pd.read_parquet(res / "verify/payload_1500kg/segments.parquet")
    summ = pd.read_csv(res / "verify/summary.csv")
    for col in ("t_s", "segment", "x_m", "q_j2_deg", "qd_j2_deg_s", "tau_j2_nm", "base_fx_n", "base_mz_nm"):
        assert col in ts.columns
    assert set(ts.path) == {"direct", "planned"} and list(summ.path) == ["direct", "planned"]
    limits = ts.attrs["capmap"]["limits"]
    for name in ("direct", "planned"):
        g = ts[ts.path == name]
        assert g.t_s.is_monotonic_increasing
        peak = max((g[c].abs() / lim).max() for c, lim in limits.items())
        row = summ.set_index("path").loc[name]
        assert row.peak_load_pct == pytest.approx(100 * peak)
        assert bool(row.loads_ok) == (peak <= 1)
        # the segment table's capacity is the minimum of the state capacities in the time series
        per_seg = g.groupby("segment").state_capacity_kg.min()
        assert np.allclose(seg[seg.path == name].set_index("segment").capacity_kg, per_seg)
    for png in ("workspace", "torques", "base_force", "base_moment"):
        assert (res / f"verify/payload_1500kg/{png}.png").stat().st_size > 10_000
    assert "1500 kg, direct" in (res / "verify/summary.md").read_text()


def _query(tmp, cfg, *args) -> dict:
    res = subprocess.run([sys.executable, "-m", "capmap", "query", *args, "--configfile", str(cfg), "--json"], cwd=tmp,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    return json.loads(res.stdout)


def test_query_line_equals_the_verify_stage_and_point_reads_the_map(run_dir):
    """``query line`` from the task's start to its goal on the arm's own configuration is the verify
    stage's direct line; ``query point`` reads the run's voxel value where the point lies."""
    tmp, cfg = run_dir
    res = tmp / "results" / "tiny"
    got = _query(tmp, cfg, "line", *map(str, X_INI), *map(str, X_DES), "--payload", "1500")
    row = pd.read_csv(res / "verify/summary.csv").set_index("path").loc["direct"]
    for col in ("length_m", "duration_s", "capacity_kg", "peak_load_pct"):
        assert got[col] == pytest.approx(row[col], rel=1e-12, abs=1e-9), col
    assert got["feasible"] == bool(row.feasible) and got["binding"] == row.binding
    assert got["margin_pct"] == pytest.approx(row.min_margin_pct, rel=1e-12, abs=1e-9)
    ts = pd.read_parquet(res / "verify/payload_1500kg/timeseries.parquet")
    q0 = ts[ts.path == "direct"].iloc[0]
    assert all(got[f"q_start_j{j}_deg"] == pytest.approx(q0[f"q_j{j}_deg"], abs=1e-9) for j in range(2, 8))
    vox = pd.read_parquet(res / "voxels/voxels.parquet")
    p = X_DES
    g = vox.attrs["capmap"]["grid"]
    i, j, k = ((p - np.array(g["lower_m"])) // g["edge_m"]).astype(int)
    pt = _query(tmp, cfg, "point", *map(str, p), "--payload", "1500")
    by_ijk = vox.set_index(["i", "j", "k"])
    assert [i, j, k] in pt["voxel"]["voxels"]
    touched = by_ijk.loc[[tuple(v) for v in pt["voxel"]["voxels"]]]
    assert pt["voxel"]["map_kg"] == pytest.approx(touched[touched.n_reachable > 0].capacity_kg.min())
    # the verdict: the arm's configuration (of its start) and whether its least branch carries the payload
    mine = [b for b in pt["branches"] if b["arms"]]
    assert {b["configuration"] for b in mine} == {pt["arm_configuration"]}
    assert pt["verdict"]["arm_carries"] == (min(b["capacity_kg"] for b in mine) >= 1500)
    # a point on a voxel face (as a refined voxel's stored worst point often is) is answered with every voxel it
    # touches (independently: each voxel whose closed box holds the point) and the least of them; the point: the
    # sampled reachable point nearest a face, moved onto it
    lower, e = np.array(g["lower_m"]), g["edge_m"]
    pts = pd.read_parquet(res / "capacity/points.parquet").query("reachable")
    xyz = pts[["x_m", "y_m", "z_m"]].to_numpy()
    off = (xyz - lower) / e - np.round((xyz - lower) / e)
    n = int(np.argmin(np.abs(off).min(axis=1)))
    a = int(np.argmin(np.abs(off[n])))
    wp = xyz[n].copy()
    wp[a] = lower[a] + e * np.round((wp[a] - lower[a]) / e)
    lo = lower + e * vox[["i", "j", "k"]].to_numpy()
    holds = vox[np.all((wp >= lo - 1e-6) & (wp <= lo + e + 1e-6), axis=1)]
    at = _query(tmp, cfg, "point", *(repr(float(v)) for v in wp))
    assert sorted(map(tuple, at["voxel"]["voxels"])) == sorted(zip(holds.i, holds.j, holds.k)) and len(holds) >= 2
    least = holds[holds.n_reachable > 0].capacity_kg.min()
    assert at["voxel"]["map_kg"] == pytest.approx(least)
    assert len(pt["branches"]) >= 1 and all(b["configuration"] for b in pt["branches"])


def test_follow_outputs(run_dir):
    tmp, _ = run_dir
    summ = pd.read_csv(tmp / "results/tiny/follow/summary.csv").set_index("case")
    assert list(summ.index) == ["space", "ground"]
    ground = summ.loc["ground"]
    assert ground.saturated_joints == "j1" and ground.command_peak_torque_pct > 105
    assert 99.9 < ground.follower_peak_torque_pct <= 100.01 and ground.toppra_duration_s < ground.follower_duration_s
    assert ground.max_deviation_m < 1e-4
    space = summ.loc["space"]
    assert space.path == "planned path" and space.segments >= 2 and space.follower_max_violation_pct < 0.01
    ts = pd.read_parquet(tmp / "results/tiny/follow/ground/timeseries.parquet")
    for col in ("t_s", "s_cmd_m", "s_m", "sd_mps", "sdd_mps2", "tau_cmd_j1_nm", "tau_j1_nm", "lag_m", "deviation_m"):
        assert col in ts.columns
    assert ts.attrs["capmap"]["torque_limits_nm"]["tau_j1_nm"] == 14
    # stored every 2 control periods (store_period_s 0.01 s at 5 ms), each window's torque peak kept
    assert ts.attrs["capmap"]["rows"].startswith("every 2 control periods") and ts.t_s.diff().max() <= 0.01 + 1e-9
    peak = max((ts[c].abs() / v).max() for c, v in ts.attrs["capmap"]["torque_limits_nm"].items())
    assert 100 * peak == pytest.approx(ground.follower_peak_torque_pct, rel=1e-5)
    assert ts.s_m.iloc[-1] == pytest.approx(0.5, abs=1e-4) and ts.limited.any()
    for case in ("space", "ground"):
        for png in ("progress", "torques"):
            assert (tmp / f"results/tiny/follow/{case}/{png}.png").stat().st_size > 10_000


def test_reconfig_outputs(run_dir):
    tmp, _ = run_dir
    res = tmp / "results" / "tiny" / "reconfig"
    runs = {m: pd.read_parquet(res / f"{m}.parquet") for m in ("nullspace", "pinv")}
    for method, df in runs.items():
        meta = df.attrs["capmap"]
        assert meta["status"] == "completed" and meta["unlocked"] == "arm1.P1" and len(meta["moving_joints"]) == 10
        for col in ("t_s", "q_arm2_j1_deg", "qd_arm1_j3_deg_s", "q_arm1_j1_deg", "passive_theta_deg", "passive_d_m",
                    "manipulability", "dm_dt", "closure_pos_err_m", "closure_rot_err_rad"):
            assert col in df.columns
        assert df.closure_pos_err_m.max() < 1e-9 and df.closure_rot_err_rad.max() < 1e-9
        assert df.passive_d_m.iloc[-1] == pytest.approx(0.3) and df.passive_theta_deg.iloc[-1] == pytest.approx(20)
        assert (df.qd_arm1_j1_deg_s == 0).all()  # the short side keeps still
    assert runs["nullspace"].dm_dt.min() >= -1e-9
    summ = pd.read_csv(res / "summary.csv").set_index("method")
    assert summ.loc["nullspace", "m_final"] > summ.loc["nullspace", "m_initial"] > summ.loc["pinv", "m_final"]
    html = (res / "animation.html").read_text()
    assert len(html) > 100_000 and "MeshCat" in html and "http://" not in html.split("<script>")[0]
    for png in ("manipulability", "joint_rates", "passive_joint"):
        assert (res / f"{png}.png").stat().st_size > 10_000


def test_dualarm_outputs(run_dir):
    tmp, _ = run_dir
    res = tmp / "results" / "tiny" / "dualarm"
    traj = pd.read_parquet(res / "trajectory.parquet")
    joints = traj.attrs["capmap"]["joints"]
    assert len(joints) == 14 and len(traj) == 101  # the tiny horizon: N = 100
    for col in ("t_s", "closed_chain_pos_err_m", "closed_chain_rot_err_rad", "path_err_m", "min_distance_m",
                "min_distance_pair", f"q_{joints[0]}_rad", f"qd_{joints[13]}_rad_s", f"u_{joints[6]}_rad_s2"):
        assert col in traj.columns
    assert traj.attrs["capmap"]["converged"]
    assert traj.closed_chain_pos_err_m.max() < 7e-7 and traj.path_err_m.max() < 7e-7 and traj.path_err_rad.max() < 1e-6
    fine = pd.read_parquet(res / "fine.parquet")
    assert len(fine) == 3 * 100 + 1 and fine.min_distance_m.min() >= 0  # fine_factor 3
    q = traj[[f"q_{j}_rad" for j in joints]].to_numpy()
    meta = traj.attrs["capmap"]
    assert np.all(q >= np.array(meta["q_lower"]) - 1e-9) and np.all(q <= np.array(meta["q_upper"]) + 1e-9)
    env = pd.read_parquet(res / "environment.parquet")
    caps = pd.read_parquet(res / "robot_capsules.parquet")
    assert len(env) > 5 and {"kind", "radius_m"} <= set(env.columns) and len(caps) >= 14
    check = pd.read_csv(res / "csqp_check.csv").set_index("solver")
    assert check.converged.all() and check.loc["AL-FDDP", "max_q_diff_rad"] < 1e-3
    html = (res / "animation.html").read_text()
    assert len(html) > 100_000 and "MeshCat" in html
    for png in ("constraint_errors", "distances", "joints", "velocities", "convergence"):
        assert (res / f"{png}.png").stat().st_size > 10_000


def test_atlas_maps_agree_with_the_main_run_and_rerun_alone(run_dir, tmp_path):
    tmp, cfg = run_dir
    res = subprocess.run(["snakemake", "atlas", "-s", str(ROOT / "Snakefile"), "-d", str(tmp), "--cores", "2",
                          "--configfile", str(cfg)], capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    atlas = pd.read_parquet(tmp / "results/tiny/atlas/atlas.parquet")
    assert len(atlas) == 2 * 2 * 1 and set(atlas.joint) == {1, 4} and set(atlas.angle_deg) == {100.0, 130.0}
    # joint 1 at 100 deg is the main run's lock: the same start, so the same direct-line capacity
    row = atlas[(atlas.joint == 1) & (atlas.angle_deg == 100)].iloc[0]
    summ = pd.read_csv(tmp / "results/tiny/verify/summary.csv").set_index(["payload_kg", "path"])
    assert row.start_reachable and row.direct_capacity_kg == pytest.approx(summ.loc[(1500, "direct"), "capacity_kg"],
                                                                           rel=1e-12)
    assert row.start_branch_offset_deg == pytest.approx(0.54, abs=0.01)
    # every map's summary agrees with its own voxels (reachable volume, volume carrying the payload)
    for _, r in atlas.iterrows():
        vox = pd.read_parquet(tmp / f"results/tiny/atlas/joint{r.joint}_angle{r.angle_deg:g}/voxels.parquet")
        reach = vox[vox.n_reachable > 0]
        assert r.reachable_volume_m3 == pytest.approx(len(reach) * 27.0)
        assert r.volume_carrying_payload_m3 == pytest.approx((reach.capacity_kg >= r.payload_kg).sum() * 27.0)
    curves = pd.read_parquet(tmp / "results/tiny/atlas/curves.parquet")
    assert len(curves) == 4 * 101 and (curves.groupby(["joint", "angle_deg"]).volume_m3.diff().dropna() <= 0).all()
    cat = pd.read_parquet(tmp / "results/tiny/atlas/catalogue.parquet")
    assert len(cat) == 4 * 2 + 2
    # another angle: one new map and the table; nothing of the main run
    jobs = planned_jobs_of(tmp, config_file(tmp_path, **{"atlas.angles_deg": [100, 130, 160]}), "atlas")
    assert jobs == {"atlas_map": 2, "atlas_tables": 1, "atlas_catalogue": 1, "atlas": 1}


def test_payload_without_a_path_is_reported_not_fatal(run_dir, tmp_path):
    tmp, _ = run_dir
    work = tmp_path / "w"
    shutil.copytree(tmp, work, symlinks=True)
    res = snakemake_run(work, config_file(tmp_path, **{"task.payload_kg": [1500, 90000]}))
    assert res.returncode == 0, res.stderr[-2000:]
    wp = pd.read_parquet(work / "results/tiny/plan/payload_90000kg/waypoints.parquet")
    assert len(wp) == 0 and wp.attrs["capmap"]["status"] == "no_path"
    reason = "no path executable on the start's IK branch ({} of {}) carrying task.payload_kg = 90000"  # branch moves
    assert re.match(re.escape(reason).replace(r"\{\}", r"\d+"), wp.attrs["capmap"]["reason"]), wp.attrs["capmap"]["reason"]
    summ = pd.read_csv(work / "results/tiny/verify/summary.csv").set_index(["payload_kg", "path"])
    assert "carrying task.payload_kg = 90000" in summ.loc[(90000, "planned"), "planner"]
    direct = summ.loc[(90000, "direct")]
    assert not direct.loads_ok and not direct.feasible and direct.limits_exceeded_at_payload


def test_refined_voxels_never_exceed_their_sampled_minima(tmp_path):
    """The refine and voxel_map stages on the tiny config with refinement on: every refined value
    is at most the sampled one, attained at a point inside its voxel (the stored worst point), and
    the per-axis values are at least the isotropic value's lower bound 0."""
    cfg = config_file(tmp_path, **{"voxels.refine": {"min_points": 8, "max_points": 16, "near_min_points": 16}})
    res = subprocess.run(["snakemake", "results/tiny/voxels/voxels.parquet", "-s", str(ROOT / "Snakefile"), "-d",
                          str(tmp_path), "--cores", "2", "--configfile", str(cfg)], capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    vox = pd.read_parquet(tmp_path / "results/tiny/voxels/voxels.parquet")
    assert vox.attrs["capmap"]["refined"]  # its shards were temporary: merged, then deleted
    assert not list((tmp_path / "results/tiny/voxels").glob("refined_*_of_*.parquet"))
    r = vox[vox.n_reachable > 0]
    assert len(r) and (r.capacity_kg <= r.capacity_sampled_kg + 1e-9).all() and r.n_points.min() >= 8
    g = vox.attrs["capmap"]["grid"]
    lo = np.array(g["lower_m"]) + r[["i", "j", "k"]].to_numpy() * g["edge_m"]
    w = r[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy()
    assert np.all((w >= lo - 1e-9) & (w <= lo + g["edge_m"] + 1e-9))
    axis = r[[c for c in vox.columns if c.startswith("capacity_along_")]].to_numpy()
    assert axis.shape[1] == 13 and np.all(axis >= 0)
    # the map per configuration: every configuration's value at least the all-branch bound, which is the
    # smallest of them; worst points inside their voxels
    conf = pd.read_parquet(tmp_path / "results/tiny/voxels/configurations.parquet")
    assert set(conf.configuration.astype(str)) <= {f"S{s}E{e}W{w}" for s in "+-" for e in "+-" for w in "+-"}
    both = conf.merge(r[["i", "j", "k", "capacity_kg"]], on=["i", "j", "k"], suffixes=("", "_all"))
    assert len(both) == len(conf) and conf.groupby(["i", "j", "k"]).size().max() > 1
    assert (both.capacity_kg >= both.capacity_kg_all - 1e-9).all()
    lowest = both.groupby(["i", "j", "k"]).agg(low=("capacity_kg", "min"), all=("capacity_kg_all", "first"))
    # the configurations' points include the one of the all-branch value (the start's worst is evaluated again)
    assert np.all(lowest.low <= lowest["all"] * (1 + 1e-9) + 1e-9)
    lo = np.array(g["lower_m"]) + conf[["i", "j", "k"]].to_numpy() * g["edge_m"]
    w = conf[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy()
    assert np.all((w >= lo - 1e-9) & (w <= lo + g["edge_m"] + 1e-9))


def test_baseline_target_the_healthy_arm_and_the_loss(tmp_path):
    """`snakemake baseline` on the tiny config with refinement on: the healthy map covers every voxel the
    failed arm reaches, is at least the failed map wherever the failed arm reached every point it tried in
    the voxel (there both are minima over the same region), the loss is healthy - failed, the convergence
    table is consistent (finer steps only add angles), and a change of the step reruns only the baseline."""
    cfg = config_file(tmp_path, **{"voxels.refine": {"min_points": 8, "max_points": 16, "near_min_points": 16},
                                   "baseline": {"step_deg": 30, "check_voxels": 6}})
    res = subprocess.run(["snakemake", "baseline", "-s", str(ROOT / "Snakefile"), "-d", str(tmp_path), "--cores", "2",
                          "--configfile", str(cfg)], capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    out = tmp_path / "results/tiny/baseline"
    bl = pd.read_parquet(out / "voxels.parquet")
    vox = pd.read_parquet(tmp_path / "results/tiny/voxels/voxels.parquet")
    failed = vox[vox.n_reachable > 0].merge(bl, on=["i", "j", "k"], suffixes=("_failed", ""))
    assert len(failed) == int((vox.n_reachable > 0).sum()) and failed.healthy_capacity_kg.notna().all()
    full = failed[failed.n_reachable == failed.n_points_failed]
    assert len(full) > 3
    tol = 0.01  # the maps' refinement: each within ~1 % of its brute force (tests/capacity/test_refine.py)
    assert np.all(full.healthy_capacity_kg >= full.capacity_kg_failed * (1 - tol) - 1e-6)
    np.testing.assert_allclose(bl.loss_kg, bl.healthy_capacity_kg - bl.capacity_kg.fillna(0.0), rtol=1e-12)
    assert bl.healthy_capacity_kg.notna().sum() >= len(failed)
    conv = pd.read_parquet(out / "convergence.parquet")
    assert len(conv) == 6 and conv.healthy_reference_kg.notna().all()  # the check's sweep reaches every worst point
    ref, got = conv.healthy_reference_kg.to_numpy(), conv.healthy_capacity_kg.to_numpy()
    zero = (ref == 0) & (got == 0)  # both 0 kg (a singular worst point): no shortfall
    np.testing.assert_allclose(conv.shortfall_rel[~zero], ((ref - got) / ref)[~zero], rtol=1e-12)
    assert np.all(conv.shortfall_rel[zero] == 0)
    assert (out / "loss.png").stat().st_size > 20_000 and len(pd.read_parquet(out / "catalogue.parquet")) == 2 + 2
    summary = pd.read_csv(out / "summary.csv").set_index("quantity").value
    assert float(summary["cost [core-s]"]) > 0
    cfg2 = config_file(tmp_path, **{"voxels.refine": {"min_points": 8, "max_points": 16, "near_min_points": 16},
                                    "baseline": {"step_deg": 20, "check_voxels": 6}})
    assert planned_jobs_of(tmp_path, cfg2, "baseline") == {"baseline_shard": 2, "baseline_map": 1, "baseline_figure": 1,
                                                           "baseline_catalogue": 1, "baseline": 1}


def test_experiments_target_is_off_the_default_path(run_dir, tmp_path):
    """The plan-gain experiment is not part of `all` (the finished tiny run has no gain files); `snakemake
    experiments` adds it beside the run without rerunning the map, with its own catalogue that
    `python -m capmap check` verifies."""
    work, cfg = run_dir
    copy = tmp_path / "run"
    shutil.copytree(work, copy, ignore=shutil.ignore_patterns("locks", "incomplete"))
    assert not (copy / "results/tiny/plan/gain.csv").exists()
    assert planned_jobs_of(copy, cfg, "experiments") == {"plan_gain": 1, "gain_catalogue": 1, "experiments": 1}
    res = subprocess.run(["snakemake", "experiments", "-s", str(ROOT / "Snakefile"), "-d", str(copy), "--cores", "2",
                          "--configfile", str(cfg)], capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    gain = pd.read_csv(copy / "results/tiny/plan/gain.csv")
    assert len(gain) > 0 and len(pd.read_parquet(copy / "results/tiny/plan/gain_catalogue.parquet")) == 1
    chk = subprocess.run([sys.executable, "-m", "capmap", "check", "results/tiny"], cwd=copy, capture_output=True,
                         text=True, timeout=300)
    assert chk.returncode == 0 and "gain_catalogue.parquet" in chk.stdout, chk.stderr[-2000:]
    assert planned_jobs(copy, cfg) == {}  # all is still complete: the experiment is beside it


def test_the_run_ends_with_a_headline_of_what_it_found(run_dir):
    """The console's last lines say per family what the run found, with numbers read here from the summary
    tables independently of capmap.stages.headline, and where the report is made."""
    tmp, _ = run_dir
    err = (tmp / "snakemake_stderr.txt").read_text()
    assert "capmap: what this run found:" in err
    head = err.split("capmap: what this run found:", 1)[1]
    out = tmp / "results" / "tiny"
    cap = pd.read_csv(out / "summary" / "capacity_summary.csv").set_index("quantity")["value"]
    assert f"capacity map: {int(float(cap['reachable voxels'])):,} reachable voxels" in head
    ver = pd.read_csv(out / "verify" / "summary.csv")
    for payload in ver.payload_kg.unique():
        assert f"{payload:g} kg" in head
    fol = pd.read_csv(out / "follow" / "summary.csv")
    assert all(f"{c} ({r}) {d:.3g} s" in head for c, r, d in zip(fol.case, fol.robot, fol.follower_duration_s))
    assert "reconfiguration: " in head and "dual-arm assembly: " in head
    assert "snakemake --report results/tiny/report.zip" in head
    assert err.count("capmap: run 'tiny'") == 1  # the config's lines once
