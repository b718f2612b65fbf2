"""Stages of the healthy-arm baseline (:mod:`capmap.capacity.healthy_map`): baseline_shard (shard k of n
of the healthy arm's voxels on the map's lattice, each voxel's minimum refined as the map's) ->
baseline_map (the healthy map beside the failed one: the loss per voxel, the angle step's
convergence, the summary)."""

from __future__ import annotations

import resource
import time

import numpy as np
import pandas as pd

from capmap.capacity.build import capacity_problem, configuration_name, refine_settings
from capmap.capacity.build_healthy import healthy_problem
from capmap.capacity.healthy_map import BASELINE_COLUMNS, angle_convergence, baseline_shard, healthy_samples, loss_table
from capmap.capacity.tables import configuration_voxels
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_quantities
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_baseline_shard", "stage_baseline_map"]


def stage_baseline_shard(voxels: str, out: str, slice_json: str, shard: int, shards: int) -> None:
    """The healthy arm's voxels with flat index % shards == shard, refined as the map's (the run's
    ``voxels.refine``); one row per voxel that a point reaches
    (:func:`capmap.capacity.healthy_map.baseline_shard`)."""
    cfg = stage_config(slice_json)
    run = cfg.run
    log = stage_logger(__name__, f"baseline shard {shard} of {shards}")
    hp = healthy_problem(run)
    rf = run.refine
    settings = None if rf is None else refine_settings(rf, run.task.payload_kg)
    rng = np.random.default_rng([0 if rf is None else rf.seed, shard, shards, 7])
    samples = healthy_samples(hp.problem.arm.robot, run.sampling, run.voxel_edge_m)
    df, meta = baseline_shard(hp, datasets.read(voxels), samples, settings, (shard, shards), rng, log)
    datasets.write(df, out, datasets.provenance("baseline", cfg.doc, shard=shard, shards=shards, **meta))
    log.info(f"done: {len(df)} voxels, {meta['points_evaluated']} points evaluated "
             f"({meta['points_evaluated'] / max(len(df), 1):.1f} per voxel), "
             f"{int((~df.converged).sum()) if settings else len(df)} not converged, {meta['seconds']:.1f} s -> {out}")


def stage_baseline_map(shards: list[str], voxels: str, configurations: str, out: Outputs, slice_json: str,
                       workers: int = 1) -> None:
    """The healthy map beside the failed one (``out["voxels"]``), the angle step's convergence at the worst
    points of ``baseline.check_voxels`` voxels (``out["convergence"]``, on ``workers`` processes) and the
    summary (``csv``, ``md``)."""
    cfg = stage_config(slice_json)
    run, bl = cfg.run, cfg.run.baseline
    log = stage_logger(__name__, "baseline map")
    parts = [datasets.read(p) for p in shards]
    h = pd.concat(parts, ignore_index=True)
    failed = datasets.read(voxels)
    problem = capacity_problem(run)
    name = configuration_name(problem.arm, run.failure.q_start_deg)
    op = configuration_voxels(failed, datasets.read(configurations), name)
    df = loss_table(h, failed, op)
    meta = parts[0].attrs["capmap"]
    cost_s = sum(p.attrs["capmap"]["seconds"] for p in parts)
    t0 = _cpu_s()
    conv = angle_convergence(healthy_problem(run, problem), healthy_problem(run, problem, reference=True), h,
                             bl.check_voxels, np.random.default_rng(run.sampling.seed), workers)
    cost_s += _cpu_s() - t0  # the check's core-seconds, its worker processes' included
    datasets.write(df[BASELINE_COLUMNS], out["voxels"], datasets.provenance(
        "baseline", cfg.doc, grid=failed.attrs["capmap"]["grid"], configuration=name, angles_deg=meta["angles_deg"],
        core_seconds=cost_s, points_evaluated=sum(p.attrs["capmap"]["points_evaluated"] for p in parts)))
    datasets.write(conv, out["convergence"], datasets.provenance("baseline", cfg.doc, step_deg=bl.step_deg,
                                                                   check_step_deg=bl.check_step_deg))
    write_quantities(_summary(run, df, conv, name, len(meta["angles_deg"]), cost_s, op is not None), out["csv"],
                     out["md"])
    log.info(f"{int(df.healthy_capacity_kg.notna().sum())} healthy voxels, {int(df.capacity_kg.notna().sum())} "
             f"failed; median loss {df.loss_kg.median():.1f} kg; {cost_s:.0f} core-s -> {out['voxels']}")


def _cpu_s() -> float:
    """CPU seconds of this process and of its ended child processes (user + system)."""
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + ru.ru_utime + ru.ru_stime


def _summary(run, df: pd.DataFrame, conv: pd.DataFrame, name: str, n_angles: int, cost_s: float,
             configurations: bool) -> list[tuple[str, object]]:
    j, bl = run.failure.joint, run.baseline
    healthy = df.healthy_capacity_kg
    rows = [(f"failed joint {j}, locked at [deg]", run.failure.angle_deg),
            (f"joint {j} angles swept (healthy arm), step [deg]", f"{n_angles}, {bl.step_deg:g}"),
            ("voxels the healthy arm reaches", int(healthy.notna().sum())),
            ("voxels the failed arm reaches (any configuration)", int(df.capacity_kg.notna().sum())),
            (f"voxels the failed arm reaches on its configuration {name}", int(df.arm_configuration_capacity_kg.notna().sum()))]
    for m in sorted(run.task.payload_kg):
        rows += [(f"voxels carrying {m:g} kg: healthy", int((healthy >= m).sum())),
                 (f"voxels carrying {m:g} kg: failed, any configuration", int((df.capacity_kg >= m).sum()))]
        if configurations:
            rows.append((f"voxels carrying {m:g} kg: failed, on {name}", int((df.arm_configuration_capacity_kg >= m).sum())))
    has = healthy.notna()
    rows += [("loss median, any configuration [kg]", round(float(df.loss_kg[has].median()), 1)),
             ("loss max, any configuration [kg]", round(float(df.loss_kg[has].max()), 1))]
    if configurations:
        rows += [(f"loss median, on {name} [kg]", round(float(df.arm_configuration_loss_kg[has].median()), 1)),
                 (f"loss max, on {name} [kg]", round(float(df.arm_configuration_loss_kg[has].max()), 1))]
    below = has & df.capacity_kg.notna() & (df.loss_kg < 0)
    rows += [("voxels where the healthy value is below the failed one (minima over different parts of the voxel)",
              int(below.sum())),
             ("healthy voxels not converged", int((has & ~df.converged.fillna(False).astype(bool)).sum())),
             (f"angle check: largest shortfall against a {bl.check_step_deg:g} deg sweep [%]",
              round(100 * float(conv.shortfall_rel.max()), 3) if len(conv) else np.nan),
             (f"angle check: voxels more than 1 % below the {bl.check_step_deg:g} deg sweep",
              int((conv.shortfall_rel > 0.01).sum())),
             ("angle check: voxels", len(conv)),
             ("cost [core-s]", round(cost_s, 1))]
    return rows
