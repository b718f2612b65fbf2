"""Stage plan_gain: the plan-gain experiment (:mod:`capmap.capacity.gain`) on the run's own map:
random tasks planned with isotropic and direction-aware moves, the latter verified."""

from __future__ import annotations

import numpy as np

from capmap.capacity.build import capacity_problem
from capmap.capacity.gain import SWEEP_PERCENTILES, GainMap, GainVerifier, gain_payloads, gain_summary, gain_tasks
from capmap.capacity.tables import AXIS_COLUMNS, grid_of
from capmap.core.dynamics import ArmDynamics
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table
from capmap.stages.common import stage_config

__all__ = ["stage_plan_gain"]


def stage_plan_gain(voxels: str, out_tasks: str, out_csv: str, out_md: str, slice_json: str) -> None:
    sc = stage_config(slice_json)
    run = sc.run
    log = stage_logger(__name__, "plan gain")
    at = capacity_problem(run)
    vox = datasets.read(voxels)
    gm = GainMap(grid_of(vox), vox.capacity_kg.to_numpy(), vox[AXIS_COLUMNS].to_numpy(), vox[["i", "j", "k"]].to_numpy())
    ver = GainVerifier(ArmDynamics(at.arm), at.rotation, at.motion, run.verification.dt_s, at.limits)
    task_payloads = sorted(run.task.payload_kg)
    payloads, sweep = gain_payloads(gm.capacity_kg, task_payloads)
    log.info(f"payloads: the task's {task_payloads} and the map's percentiles {SWEEP_PERCENTILES} of the positive "
             f"voxel capacities, {sweep} kg")
    tasks = gain_tasks(gm, ver, payloads, run.planning.gain_tasks, np.random.default_rng(run.sampling.seed), log.info)
    summary = gain_summary(tasks)
    datasets.write(tasks, out_tasks, datasets.provenance("plan_gain", sc.doc))
    write_table(summary, out_csv, out_md)
    for r in summary.to_dict("records"):
        log.info(f"{r['payload_kg']:g} kg: {r['tasks']} tasks, isotropic A* finds {r['isotropic_path']}, direction-aware "
                 f"{r['axis_path']}; gained {r['gained_by_axis_moves']}, of which {r['gained_tracked']} tracked and "
                 f"{r['gained_verified_carrying']} verified carrying the payload; direct line fails where the "
                 f"verified detour carries it: {r['direct_line_fails_detour_carries']} -> {out_csv}")
