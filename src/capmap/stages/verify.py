"""Stages of planning and verification (:mod:`capmap.capacity.plan_verify`): plan (A* per payload or
task) -> verify (direct line and the planned path, carrying the payload) -> verify_plots; one job per
payload or task."""

from __future__ import annotations

from capmap.capacity.build import capacity_problem
from capmap.capacity.plan_verify import no_waypoints, plan_waypoints, verify_job
from capmap.capacity.tables import grid_of
from capmap.errors import CapmapError, ConfigError, NoPath
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table
from capmap.stages.common import stage_config

__all__ = ["PLAN_KEYS", "stage_plan", "stage_verify"]

PLAN_KEYS = {"start": "task.start_m", "goal": "task.goal_m", "payload": "task.payload_kg",
             "q_ini": "task.q_ini_deg"}  # planning's roles


def stage_plan(voxels: str, out: str, slice_json: str) -> None:
    """Plan through the voxels that carry the task payload (``planning.moves``: on the executed
    branch, or A* on the map's axis or isotropic values); a payload with no path is recorded
    (status ``no_path`` and the reason in the provenance, zero waypoints), not an error."""
    sc = stage_config(slice_json)
    job, pl = sc.job, sc.run.planning
    log = stage_logger(__name__, f"plan {job.payload_kg:g} kg")
    vox = datasets.read(voxels)
    status, reason, cost, expanded = "ok", "", float("nan"), 0
    try:
        df, cost, expanded, line = plan_waypoints(capacity_problem(sc.run), vox, grid_of(vox), job, pl.moves,
                                                  pl.track_step_m)
        log.info(line)
    except NoPath as exc:
        status, reason, df = "no_path", exc.in_terms(**PLAN_KEYS), no_waypoints()
        log.info(f"no path: {reason}")
    except CapmapError as exc:  # start or goal outside the map: the config's fault
        raise ConfigError(exc.in_terms(**PLAN_KEYS)) from None
    datasets.write(df, out, datasets.provenance("plan", sc.doc, payload_kg=job.payload_kg, status=status, reason=reason,
                                                 cost_m=cost, expanded=expanded, moves=pl.moves))


def stage_verify(waypoints: str, out_timeseries: str, out_segments: str, out_csv: str, out_md: str,
                 slice_json: str) -> None:
    """Verify the direct line and the planned path (if any) carrying the task payload."""
    sc = stage_config(slice_json)
    problem, job = capacity_problem(sc.run), sc.job
    log = stage_logger(__name__, f"verify {job.payload_kg:g} kg")
    wp = datasets.read(waypoints)
    plan = wp.attrs["capmap"]
    ts, seg, summary = verify_job(problem, job, wp, plan, sc.run.verification.dt_s, log)
    limits = problem.limits
    prov = datasets.provenance("verify", sc.doc, payload_kg=job.payload_kg,
                               limits=dict(zip(limits.names, limits.limit.tolist())), plan_status=plan["status"],
                               plan_reason=plan["reason"])
    datasets.write(ts, out_timeseries, prov)
    datasets.write(seg, out_segments, prov)
    write_table(summary, out_csv, out_md)
