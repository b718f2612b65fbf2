"""The capacity family's stages called one after another as the rules call them (their slices from
capmap.config.slices, no Snakemake) on a tiny map: 300 joint samples, 2 m voxels, 12 directions, every
voxel refined a little. Each stage's output is held against an independent computation: capacities
against Pinocchio's per-configuration path, voxel minima against a pandas groupby, the refinement
against its own start (never above it, every value attained at its worst point), the plan against
the map, the verification against its own samples' loads, the healthy arm against the locked one."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from capmap.capacity.baseline import healthy_capacity
from capmap.capacity.build import capacity_problem
from capmap.capacity.build_healthy import healthy_problem
from capmap.capacity.engine import capacity_over_directions, coefficients_pinocchio
from capmap.checks import check_run_config
from capmap.config import canonical, main_task, stage_slice
from capmap.config.validation import load_yaml
from capmap.errors import CapmapError
from capmap.io import datasets
from capmap.stages.atlas import stage_atlas_map
from capmap.stages.baseline import stage_baseline_shard
from capmap.stages.capacity import stage_capacity, stage_model, stage_points, stage_sample, stage_voxels
from capmap.stages.refine import stage_refine, stage_voxel_map
from tests.scenario import ROOT

SHARDS = 2


def _doc() -> dict:
    doc = copy.deepcopy(load_yaml(ROOT / "tests" / "data" / "tiny.yaml"))
    for key in ("follow", "reconfig", "dualarm"):
        doc.pop(key, None)
    doc.update(run="stages", shards=SHARDS, voxels={"edge_m": 2.0, "refine": {"min_points": 4, "max_points": 24,
                                                                               "near_min_points": 8}},
               baseline={"step_deg": 60, "check_voxels": 3},
               atlas={"joints": [4], "angles_deg": [130], "edge_m": 3.0, "directions": {"kind": "sphere", "n": 12},
                      "sampling": {"mode": "voxel_fill", "n_points": 150, "jitter_per_voxel": 0, "seed": 3}})
    doc["robot"] = str(ROOT / doc["robot"])
    return doc


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The tiny run's checked config and its folder with every capacity stage's output in it."""
    cfg = check_run_config(_doc(), "stages.yaml")
    d = tmp_path_factory.mktemp("stages")

    def sl(stage, job=None):
        return canonical(stage_slice(cfg, stage, job))

    stage_model(cfg.robot, str(d / "joints.parquet"), sl("model"))
    stage_sample(str(d / "points.parquet"), sl("sample"))
    for k in range(SHARDS):
        stage_capacity(str(d / "points.parquet"), str(d / f"cap{k}.parquet"), sl("capacity"), k, SHARDS)
    stage_points([str(d / f"cap{k}.parquet") for k in range(SHARDS)], str(d / "cappoints.parquet"), sl("capacity"))
    stage_voxels(str(d / "cappoints.parquet"), str(d / "sampled.parquet"), sl("voxels"))
    for k in range(SHARDS):
        stage_refine(str(d / "sampled.parquet"), str(d / f"ref{k}.parquet"), str(d / f"conf{k}.parquet"), sl("refine"),
                     k, SHARDS)
    stage_voxel_map(str(d / "sampled.parquet"), [str(d / f"ref{k}.parquet") for k in range(SHARDS)],
                    [str(d / f"conf{k}.parquet") for k in range(SHARDS)], str(d / "voxels.parquet"),
                    str(d / "configurations.parquet"), sl("refine"))
    return cfg, d, sl


def _reference(problem, points: np.ndarray) -> np.ndarray:
    """Each point's least capacity over its IK branches and the problem's directions (kg, NaN unreachable)
    by Pinocchio's per-configuration path."""
    sol = problem.branches(points)
    out = np.full(len(points), np.nan)
    for i, n in enumerate(sol.n_solutions):
        if n:
            coef = coefficients_pinocchio(problem.dyn, sol.q[i, :n])
            cap, _ = capacity_over_directions(coef, problem.directions, problem.motion, problem.dyn.gravity,
                                              problem.limits)
            out[i] = cap.min()
    return out


def test_model_and_sample_stages(run):
    cfg, d, _ = run
    joints = datasets.read(d / "joints.parquet")
    assert len(joints) == 7 and joints.mass_kg.gt(0).all()
    pts = datasets.read(d / "points.parquet")
    assert len(pts) > cfg.sampling.n_points and np.array_equal(pts.point_id, np.arange(len(pts)))


def test_capacity_stage_against_pinocchio(run):
    cfg, d, _ = run
    cap = pd.concat([datasets.read(d / f"cap{k}.parquet") for k in range(SHARDS)])
    pts = datasets.read(d / "points.parquet")
    assert sorted(cap.point_id) == sorted(pts.point_id)  # the shards split the points, none twice
    rows = cap[cap.reachable].sample(12, random_state=1)
    ref = _reference(capacity_problem(cfg), rows[["x_m", "y_m", "z_m"]].to_numpy())
    np.testing.assert_allclose(rows.capacity_kg, ref, rtol=1e-8, atol=1e-6)


def test_voxels_stage_is_the_minimum_of_its_points(run):
    _, d, _ = run
    vox = datasets.read(d / "sampled.parquet")
    pts = datasets.read(d / "cappoints.parquet")
    grid = vox.attrs["capmap"]["grid"]  # binned here, independently of the stage
    idx = np.floor((pts[["x_m", "y_m", "z_m"]].to_numpy() - grid["lower_m"]) / grid["edge_m"]).astype(int)
    pts = pts.assign(i=idx[:, 0], j=idx[:, 1], k=idx[:, 2])
    reach = pts[pts.reachable]
    least = reach.groupby(["i", "j", "k"]).capacity_kg.min()
    got = vox.set_index(["i", "j", "k"]).capacity_kg.loc[least.index]
    np.testing.assert_array_equal(got.to_numpy(), least.to_numpy())
    assert vox.n_points.sum() == len(pts)


def test_refine_stages_never_raise_a_value_and_each_is_attained(run):
    cfg, d, _ = run
    sampled, refined = datasets.read(d / "sampled.parquet"), datasets.read(d / "voxels.parquet")
    reach = refined.n_reachable > 0
    assert np.all(refined.capacity_kg[reach] <= sampled.capacity_kg[reach] + 1e-9)
    assert np.array_equal(refined.capacity_sampled_kg[reach], sampled.capacity_kg[reach])
    rows = refined[reach].sample(10, random_state=2)
    ref = _reference(capacity_problem(cfg), rows[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy())
    np.testing.assert_allclose(rows.capacity_kg, ref, rtol=1e-8, atol=1e-6)
    conf = datasets.read(d / "configurations.parquet")  # the least configuration is the all-branch value
    least = conf.groupby(["i", "j", "k"]).capacity_kg.min()
    np.testing.assert_allclose(refined.set_index(["i", "j", "k"]).capacity_kg.loc[least.index], least, atol=1e-9)


def test_refine_in_batches_keeps_every_voxel_and_its_guarantees(run, monkeypatch):
    """A shard refined in batches of 5 voxels (a job's memory bounded by the batch): the same voxels, each
    value never above its sampled one and attained at its worst point (Pinocchio's per-configuration path)."""
    import capmap.capacity.refine_map as refine_map

    cfg, d, sl = run
    monkeypatch.setattr(refine_map, "BATCH_VOXELS", 5)
    stage_refine(str(d / "sampled.parquet"), str(d / "refb.parquet"), str(d / "confb.parquet"), sl("refine"), 0, SHARDS)
    batched, whole = datasets.read(d / "refb.parquet"), datasets.read(d / "ref0.parquet")
    assert len(whole) > 10 and whole[["i", "j", "k"]].equals(batched[["i", "j", "k"]])
    sampled = datasets.read(d / "sampled.parquet").set_index(["i", "j", "k"]).capacity_kg
    assert np.all(batched.capacity_kg.to_numpy() <= sampled.loc[list(zip(batched.i, batched.j, batched.k))].to_numpy()
                  + 1e-9)
    rows = batched[batched.capacity_kg.notna()].sample(8, random_state=3)
    ref = _reference(capacity_problem(cfg), rows[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy())
    np.testing.assert_allclose(rows.capacity_kg, ref, rtol=1e-8, atol=1e-6)


def test_plan_and_verify_stages(run):
    from capmap.stages.verify import stage_plan, stage_verify

    cfg, d, sl = run
    payload = cfg.task.payload_kg[0]
    job = main_task(cfg.task, cfg.failure, payload)
    stage_plan(str(d / "voxels.parquet"), str(d / "wp.parquet"), sl("plan", job))
    wp = datasets.read(d / "wp.parquet")
    status = wp.attrs["capmap"]["status"]
    if status == "ok":  # every voxel on the path carries the payload on the map
        assert (wp.voxel_capacity_kg >= payload).all()
        np.testing.assert_allclose(wp[["x_m", "y_m", "z_m"]].iloc[[0, -1]].to_numpy(), [job.start_m, job.goal_m])
    else:
        assert status == "no_path" and len(wp) == 0
    stage_verify(str(d / "wp.parquet"), str(d / "ts.parquet"), str(d / "seg.parquet"), str(d / "v.csv"),
                 str(d / "v.md"), sl("verify", job))
    ts, summary = datasets.read(d / "ts.parquet"), pd.read_csv(d / "v.csv")
    direct = summary[summary.path == "direct"].iloc[0]
    mine = ts[ts.path == "direct"]
    # the path's capacity is the least of its samples'; feasible exactly when the payload fits under it
    assert direct.capacity_kg == pytest.approx(mine.state_capacity_kg.min(), rel=1e-12)
    names = [c for c in ts.columns if c.startswith(("tau_", "base_f", "base_m"))]
    assert names and bool(direct.feasible) == (direct.capacity_kg >= payload and direct.tracking == "ok"
                                               and direct.joint_range == "ok")


def test_baseline_stage_is_never_below_the_locked_arm(run):
    cfg, d, sl = run
    stage_baseline_shard(str(d / "voxels.parquet"), str(d / "healthy.parquet"), sl("baseline_shard"), 0, 1)
    h = datasets.read(d / "healthy.parquet")
    assert len(h) > 0
    # at a healthy voxel's worst point the healthy value is the best posture over the swept angles, and the
    # failed arm's own angle is on the sweep: never below the locked arm's value there (Pinocchio's path)
    rows = h[h.healthy_capacity_kg.notna()].sample(8, random_state=3)
    pts = rows[["worst_x_m", "worst_y_m", "worst_z_m"]].to_numpy()
    locked = _reference(capacity_problem(cfg), pts)
    ok = np.isfinite(locked)
    assert np.all(rows.healthy_capacity_kg.to_numpy()[ok] >= locked[ok] * (1 - 1e-9) - 1e-6)
    assert np.allclose(healthy_capacity(healthy_problem(cfg), pts).capacity_kg,
                       rows.healthy_capacity_kg)


def test_atlas_map_stage(run):
    cfg, d, sl = run
    stage_atlas_map(str(d / "atlas_vox.parquet"), str(d / "atlas_sum.parquet"), sl("atlas_map"), 4, 130.0)
    vox, rows = datasets.read(d / "atlas_vox.parquet"), datasets.read(d / "atlas_sum.parquet")
    assert list(rows.payload_kg) == list(cfg.task.payload_kg) and (rows.joint == 4).all()
    reach = vox[vox.n_reachable > 0]
    assert rows.reachable_volume_m3.iloc[0] == pytest.approx(len(reach) * cfg.atlas.edge_m ** 3)
    assert rows.capacity_max_kg.iloc[0] == pytest.approx(reach.capacity_kg.max())


@pytest.fixture(scope="module")
def planned(run):
    """The main task's plan and verification at its first payload (the figure stages read them)."""
    from capmap.stages.verify import stage_plan, stage_verify

    cfg, d, sl = run
    job = main_task(cfg.task, cfg.failure, cfg.task.payload_kg[0])
    if not (d / "wp.parquet").exists():
        stage_plan(str(d / "voxels.parquet"), str(d / "wp.parquet"), sl("plan", job))
        stage_verify(str(d / "wp.parquet"), str(d / "ts.parquet"), str(d / "seg.parquet"), str(d / "v.csv"),
                     str(d / "v.md"), sl("verify", job))
    return job


def test_summary_3d_and_verify_figure_stages(run, planned):
    from capmap.stages.capacity_figures import stage_capacity_3d, stage_summary
    from capmap.stages.verify_figures import stage_verify_plots

    cfg, d, sl = run
    stage_summary(str(d / "voxels.parquet"), str(d / "configurations.parquet"), str(d / "cappoints.parquet"),
                  [str(d / "wp.parquet")], {"csv": str(d / "s.csv"), "md": str(d / "s.md"), "png": str(d / "map.png")},
                  sl("view"))
    summary = pd.read_csv(d / "s.csv")
    vox = datasets.read(d / "voxels.parquet")
    reach = vox[vox.n_reachable > 0]
    text = " ".join(map(str, summary.to_numpy().ravel()))
    assert str(len(reach)) in text or f"{len(reach):,}" in text  # the reachable voxels, counted independently
    assert (d / "map.png").stat().st_size > 10_000
    stage_capacity_3d(str(d / "voxels.parquet"), str(d / "configurations.parquet"), [str(d / "wp.parquet")],
                      str(d / "map.html"), sl("view"))
    html = (d / "map.html").read_text()
    assert "Plotly" in html and "capmap-3d" in html
    pngs = {n: str(d / f"{n}.png") for n in ("workspace", "torques", "force", "moment")}
    stage_verify_plots(str(d / "voxels.parquet"), str(d / "configurations.parquet"), str(d / "ts.parquet"), pngs,
                       sl("verify", planned))
    assert all(Path(p).stat().st_size > 10_000 for p in pngs.values())


def test_gain_stage_on_the_tiny_map(run):
    from capmap.stages.gain import stage_plan_gain

    cfg, d, sl = run
    stage_plan_gain(str(d / "voxels.parquet"), str(d / "gain.parquet"), str(d / "gain.csv"), str(d / "gain.md"),
                    sl("gain"))
    tasks, summary = datasets.read(d / "gain.parquet"), pd.read_csv(d / "gain.csv")
    assert set(summary.payload_kg) == set(tasks.payload_kg)
    for m, grp in tasks.groupby("payload_kg"):  # the summary counts the task table's rows
        assert int(summary.set_index("payload_kg").loc[m, "tasks"]) == len(grp)


def test_baseline_map_and_figure_stages(run):
    from capmap.stages.baseline import stage_baseline_map
    from capmap.stages.capacity_figures import stage_baseline_figure

    cfg, d, sl = run
    if not (d / "healthy.parquet").exists():
        stage_baseline_shard(str(d / "voxels.parquet"), str(d / "healthy.parquet"), sl("baseline_shard"), 0, 1)
    stage_baseline_map([str(d / "healthy.parquet")], str(d / "voxels.parquet"), str(d / "configurations.parquet"),
                       {"voxels": str(d / "b.parquet"), "convergence": str(d / "conv.parquet"), "csv": str(d / "b.csv"),
                        "md": str(d / "b.md")}, sl("baseline"))
    b = datasets.read(d / "b.parquet")
    both = b.healthy_capacity_kg.notna()
    np.testing.assert_allclose(b.loss_kg[both], (b.healthy_capacity_kg - b.capacity_kg.fillna(0.0))[both])
    conv = datasets.read(d / "conv.parquet")
    assert len(conv) == min(cfg.baseline.check_voxels, int(both.sum()))
    stage_baseline_map([str(d / "healthy.parquet")], str(d / "voxels.parquet"), str(d / "configurations.parquet"),
                       {"voxels": str(d / "b2.parquet"), "convergence": str(d / "conv2.parquet"), "csv": str(d / "b2.csv"),
                        "md": str(d / "b2.md")}, sl("baseline"), workers=2)  # the check on two processes: same rows
    pd.testing.assert_frame_equal(datasets.read(d / "conv2.parquet"), conv)
    stage_baseline_figure(str(d / "b.parquet"), str(d / "conv.parquet"), str(d / "loss.png"), sl("view"))
    assert (d / "loss.png").stat().st_size > 10_000


def test_atlas_tables_stage(run):
    from capmap.stages.atlas import stage_atlas

    cfg, d, sl = run
    if not (d / "atlas_sum.parquet").exists():
        stage_atlas_map(str(d / "atlas_vox.parquet"), str(d / "atlas_sum.parquet"), sl("atlas_map"), 4, 130.0)
    out = dict(atlas=str(d / "atlas.parquet"), curves=str(d / "curves.parquet"), heatmap=str(d / "heat.png"),
               curves_png=str(d / "curves.png"))
    stage_atlas([str(d / "atlas_sum.parquet")], [str(d / "atlas_vox.parquet")], out, sl("atlas"))
    curves = datasets.read(d / "curves.parquet")
    vox = datasets.read(d / "atlas_vox.parquet")
    reach = vox.capacity_kg[vox.n_reachable > 0].to_numpy()
    for m, vol in zip(curves.payload_kg[::17], curves.volume_m3[::17]):  # the volume carrying m, counted here
        assert vol == pytest.approx((reach >= m).sum() * cfg.atlas.edge_m ** 3)


def test_voxel_map_gathers_configuration_rows_chunk_by_chunk(run, monkeypatch):
    """The map's configuration rows read 7 at a time (a job holds a chunk, not the map's table) equal the
    refine shards' rows gathered whole and sorted (pandas), the axis capacities as stored (float32, never
    above the computed value); shards given out of order are refused (not written unsorted)."""
    import capmap.stages.refine as refine_stage

    _, d, sl = run
    monkeypatch.setattr(refine_stage, "CHUNK_ROWS", 7)
    confs = [str(d / f"conf{k}.parquet") for k in range(SHARDS)]
    refs = [str(d / f"ref{k}.parquet") for k in range(SHARDS)]
    stage_voxel_map(str(d / "sampled.parquet"), refs, confs, str(d / "voxels7.parquet"), str(d / "conf7.parquet"),
                    sl("refine"))
    got = datasets.read(d / "conf7.parquet")
    whole = pd.concat([datasets.read(p) for p in confs], ignore_index=True)
    whole = whole.sort_values(["i", "j", "k", "configuration"], ignore_index=True)  # in the labels' order
    assert len(got) == len(whole) > 7 and got.attrs["capmap"]["configurations"] == list(got.configuration.cat.categories)
    for col in got.columns:
        a, b = got[col], whole[col]
        if col.startswith("capacity_along_"):
            assert np.all((a.to_numpy(float) <= b.to_numpy()) | b.isna().to_numpy())
            np.testing.assert_allclose(a.to_numpy(float), b.to_numpy(), rtol=2e-7)
        else:
            assert a.astype(str).tolist() == b.astype(str).tolist(), col
    with pytest.raises(CapmapError, match="order"):
        stage_voxel_map(str(d / "sampled.parquet"), refs, confs[::-1], str(d / "voxelsr.parquet"),
                        str(d / "confr.parquet"), sl("refine"))
