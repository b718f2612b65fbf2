"""Stages of the voxel refinement (:mod:`capmap.capacity.refine_map`): refine (shard k of n of the
reachable voxels: each voxel's minimum refined until it converges) -> voxel_map (the sampled voxels
with the refined values: the map every later stage reads)."""

from __future__ import annotations

import numpy as np

from capmap.capacity.build import capacity_problem, refine_settings
from capmap.capacity.refine_map import merge_refined, refine_shard
from capmap.capacity.tables import axes_stored
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.stages.common import stage_config

__all__ = ["stage_refine", "stage_voxel_map"]


def stage_refine(voxels: str, out: str, out_configurations: str, slice_json: str, shard: int, shards: int) -> None:
    """Refine shard ``shard`` of the reachable voxels, all branches and each configuration; write one row
    per voxel (``out``) and one per voxel x configuration met there (``out_configurations``)."""
    cfg = stage_config(slice_json)
    run = cfg.run
    log = stage_logger(__name__, f"refine shard {shard} of {shards}")
    problem = capacity_problem(run, per_configuration=True)
    rs = refine_shard(datasets.read(voxels), problem, refine_settings(run.refine, run.task.payload_kg), shard, shards,
                      np.random.default_rng([run.refine.seed, shard, shards]), log)
    labels = problem.labels
    datasets.write(rs.configurations, out_configurations, datasets.provenance(
        "refine", cfg.doc, shard=shard, shards=shards, configurations=list(labels.names), labels=labels.description))
    datasets.write(rs.voxels, out, datasets.provenance("refine", cfg.doc, shard=shard, shards=shards,
                                                        rounds=rs.rounds, points_evaluated=rs.n_evaluated))
    drop = (rs.start_kg - rs.capacity_kg) / np.where(rs.start_kg > 0, rs.start_kg, 1.0)
    log.info(f"done: {len(rs.voxels)} voxels in {rs.rounds} rounds, {rs.n_evaluated} points evaluated "
             f"({rs.n_evaluated / max(len(rs.voxels), 1):.1f} per voxel), {int((~rs.converged).sum())} not converged; "
             f"values lowered by up to {100 * np.max(drop, initial=0):.1f} % (median "
             f"{100 * np.median(drop) if len(drop) else 0:.2f} %) -> {out}")


def stage_voxel_map(sampled: str, refined: list[str], configurations: list[str], out: str, out_configurations: str,
                    slice_json: str) -> None:
    """The sampled voxel table with each refined voxel's values (:func:`capmap.capacity.refine_map.merge_refined`;
    without refinement the sampled table as is, and no configuration rows)."""
    cfg = stage_config(slice_json)
    parts = [datasets.read(p) for p in configurations]
    meta = parts[0].attrs["capmap"] if parts else {"configurations": [], "labels": ""}
    vox, conf = merge_refined(datasets.read(sampled), [datasets.read(p) for p in refined], parts, meta["configurations"])
    grid = vox.attrs["capmap"]["grid"]
    datasets.write(vox, out, datasets.provenance("voxels", cfg.doc, grid=grid, refined=bool(refined)))
    datasets.write(axes_stored(conf), out_configurations, datasets.provenance("voxels", cfg.doc, grid=grid, refined=bool(refined),
                                                                 configurations=meta["configurations"],
                                                                 labels=meta["labels"]))
    reach = vox.n_reachable > 0
    drop = (vox.capacity_sampled_kg - vox.capacity_kg)[reach] / vox.capacity_sampled_kg[reach].where(
        vox.capacity_sampled_kg[reach] > 0, 1.0)
    stage_logger(__name__, "voxel map").info(
        f"{int(reach.sum())} reachable voxels, {int(vox.n_points.sum())} points; refined: {bool(refined)}"
        + (f", {int((reach & ~vox.converged).sum())} not converged, values lowered by up to {100 * drop.max():.1f} %"
           if refined else "") + f" -> {out}")
