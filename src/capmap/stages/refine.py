"""Stages of the voxel refinement (:mod:`capmap.capacity.refine_map`): refine (shard k of n of the
reachable voxels: each voxel's minimum refined until it converges) -> voxel_map (the sampled voxels
with the refined values: the map every later stage reads)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from capmap.capacity.build import capacity_problem, refine_settings
from capmap.capacity.refine_map import configuration_rows, merge_refined, refine_shard
from capmap.capacity.tables import grid_of
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.stages.common import stage_config

__all__ = ["stage_refine", "stage_voxel_map"]

CHUNK_ROWS = 200_000  # configuration rows the voxel map holds at a time (~60 MB)


def stage_refine(voxels: str, out: str, out_configurations: str, slice_json: str, shard: int, shards: int) -> None:
    """Refine shard ``shard`` of the reachable voxels, all branches and each configuration; write one row
    per voxel (``out``) and one per voxel x configuration met there (``out_configurations``, batch by
    batch as the refinement goes: :func:`capmap.capacity.refine_map.refine_shard`)."""
    cfg = stage_config(slice_json)
    run = cfg.run
    log = stage_logger(__name__, f"refine shard {shard} of {shards}")
    problem = capacity_problem(run, per_configuration=True)
    batches = refine_shard(datasets.read(voxels), problem, refine_settings(run.refine, run.task.payload_kg), shard,
                           shards, np.random.default_rng([run.refine.seed, shard, shards]), log)
    done = []

    def configurations():
        for b in batches:
            done.append(replace(b, configurations=None))
            yield b.configurations

    labels = problem.labels
    datasets.write_chunks(configurations(), out_configurations, datasets.provenance(
        "refine", cfg.doc, shard=shard, shards=shards, configurations=list(labels.names), labels=labels.description))
    vox = pd.concat([b.voxels for b in done], ignore_index=True)
    rounds, n_evaluated = max(b.rounds for b in done), sum(b.n_evaluated for b in done)
    datasets.write(vox, out, datasets.provenance("refine", cfg.doc, shard=shard, shards=shards,
                                                 rounds=rounds, points_evaluated=n_evaluated))
    start = np.concatenate([b.start_kg for b in done])
    drop = (start - vox.capacity_kg.to_numpy()) / np.where(start > 0, start, 1.0)
    log.info(f"done: {len(vox)} voxels in {rounds} rounds (the most of any batch), {n_evaluated} points evaluated "
             f"({n_evaluated / max(len(vox), 1):.1f} per voxel), {int((~vox.converged).sum())} not converged; "
             f"values lowered by up to {100 * np.max(drop, initial=0):.1f} % (median "
             f"{100 * np.median(drop) if len(drop) else 0:.2f} %) -> {out}")


def stage_voxel_map(sampled: str, refined: list[str], configurations: list[str], out: str, out_configurations: str,
                    slice_json: str) -> None:
    """The sampled voxel table with each refined voxel's values (:func:`capmap.capacity.refine_map.merge_refined`;
    without refinement the sampled table as is, and no configuration rows); the refine shards'
    configuration rows gathered chunk by chunk (:func:`capmap.capacity.refine_map.configuration_rows`), so
    that the job holds one chunk of them, not the map's."""
    cfg = stage_config(slice_json)
    meta = datasets.read_provenance(configurations[0]) if configurations else {"configurations": [], "labels": ""}
    vox = merge_refined(datasets.read(sampled), [datasets.read(p) for p in refined])
    grid = vox.attrs["capmap"]["grid"]
    datasets.write(vox, out, datasets.provenance("voxels", cfg.doc, grid=grid, refined=bool(refined)))
    chunks = (c for p in configurations for c in datasets.read_chunks(p, CHUNK_ROWS))
    datasets.write_chunks(configuration_rows(chunks, grid_of(vox), meta["configurations"]), out_configurations,
                          datasets.provenance("voxels", cfg.doc, grid=grid, refined=bool(refined),
                                              configurations=meta["configurations"], labels=meta["labels"]))
    reach = vox.n_reachable > 0
    drop = (vox.capacity_sampled_kg - vox.capacity_kg)[reach] / vox.capacity_sampled_kg[reach].where(
        vox.capacity_sampled_kg[reach] > 0, 1.0)
    stage_logger(__name__, "voxel map").info(
        f"{int(reach.sum())} reachable voxels, {int(vox.n_points.sum())} points; refined: {bool(refined)}"
        + (f", {int((reach & ~vox.converged).sum())} not converged, values lowered by up to {100 * drop.max():.1f} %"
           if refined else "") + f" -> {out}")
