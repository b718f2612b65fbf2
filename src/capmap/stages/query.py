"""``python -m capmap query``: a run's config in, a question answered (:mod:`capmap.capacity.query`)
and the run's voxel values at the point, as a printed table or JSON. Reads the config as the
workflow checks it and, when they are of that config, the run's voxel maps."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.capacity.build import capacity_problem
from capmap.capacity.engine import margin_pct
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.query import line_query, point_query
from capmap.capacity.tables import grid_of
from capmap.checks import check_run_config
from capmap.config.estimate import check_duration, check_steps, line_duration_s
from capmap.config.run import RunConfig, run_document
from capmap.config.slices import stage_slice
from capmap.errors import CapmapError
from capmap.io import datasets

__all__ = ["load_question", "answer_point", "answer_line"]

def load_question(configfile: str) -> tuple[RunConfig, CapacityProblem]:
    """The checked run config of ``configfile`` and the capacity problem it asks about (per configuration)."""
    run = check_run_config(run_document([configfile]), configfile)
    return run, capacity_problem(run, per_configuration=True)


def _run_voxels(run: RunConfig, results: Path, point: np.ndarray) -> dict:
    """The run's voxel values at the point: {"voxel": (i, j, k), "map_kg": all-branch, "configurations":
    {name: kg}, "note": why there are none}."""
    base = results / run.name / "voxels"
    path, conf_path = base / "voxels.parquet", base / "configurations.parquet"
    if not path.is_file():
        return {"note": f"no voxel map at {path} (run: snakemake --cores 2 capacity_map)"}
    try:
        vox = datasets.read(path)
        have = {k: v for k, v in vox.attrs["capmap"]["config"].items() if k != "code"}
    except (CapmapError, KeyError, TypeError, AttributeError) as exc:
        return {"note": f"{path} is not a voxel map capmap wrote ({exc}); rerun: snakemake --cores 2 capacity_map"}
    want = {k: v for k, v in stage_slice(run, "refine").items() if k != "code"}
    if datasets.canonical(want) != datasets.canonical(have):
        return {"note": f"{path} is of another config than this one (rerun: snakemake --cores 2 capacity_map)"}
    grid = grid_of(vox)
    idx = grid.index(point[None])[0]
    if np.any(idx < 0):
        return {"note": "outside the run's voxel grid"}
    row = vox.iloc[int(grid.flat(idx[None])[0])]
    bound = float(row.capacity_kg) if row.n_reachable > 0 and np.isfinite(row.capacity_kg) else None  # JSON: null
    out = {"voxel": [int(v) for v in idx], "map_kg": bound, "configurations": {}}
    if conf_path.is_file():
        conf = datasets.read(conf_path)
        mine = conf[(conf.i == idx[0]) & (conf.j == idx[1]) & (conf.k == idx[2])]
        out["configurations"] = {str(c): float(v) for c, v in zip(mine.configuration, mine.capacity_kg) if np.isfinite(v)}
    return out


def answer_point(configfile: str, point, payload_kg: float | None, as_json: bool, results: str = "results") -> str:
    """The text (or JSON) answer to ``query point``."""
    run, q = load_question(configfile)
    p = np.asarray(point, dtype=float)
    ans = point_query(q, p)
    vox = _run_voxels(run, Path(results), p)
    arm = q.dyn.arm
    u = np.round(ans.worst_u, 4) + 0.0  # a unit vector: 4 decimals (and no -0)
    df = pd.DataFrame({"configuration": ans.configuration, "capacity_kg": ans.capacity_kg, "binding": ans.binding,
                       "worst_ux": u[:, 0], "worst_uy": u[:, 1], "worst_uz": u[:, 2]})
    if payload_kg is not None:
        df["margin_pct"] = margin_pct(ans.capacity_kg, payload_kg)
        df["carries"] = ans.capacity_kg >= payload_kg
    voxel_cfg = vox.get("configurations", {})
    df["voxel_capacity_kg"] = [voxel_cfg.get(c, np.nan) for c in ans.configuration]
    for c, j in enumerate(arm.active_joint_numbers):
        df[f"q_j{j}_deg"] = np.rad2deg(ans.q_rad[:, c])
    if as_json:
        return json.dumps({"point_m": p.tolist(), "payload_kg": payload_kg, "run": run.name, "voxel": vox,
                           "branches": json.loads(df.to_json(orient="records"))}, indent=1)
    head = (f"capmap: run {run.name!r}, {run.failure.describe()}\npoint [{', '.join(f'{v:g}' for v in p)}] m at the task "
            f"orientation: {len(df)} IK branches on {df.configuration.nunique()} configurations "
            f"({q.labels.description})")
    if "note" in vox:
        tail = f"run's voxel map: {vox['note']}"
    else:
        bound = "no sampled point reached" if vox["map_kg"] is None else f"{vox['map_kg']:.1f} kg for any configuration"
        tail = (f"run's voxel {tuple(vox['voxel'])}: {bound} (the all-branch bound); voxel_capacity_kg: each "
                f"configuration's minimum over the voxel")
    return "\n".join([head, df.to_string(index=False, float_format=lambda v: f"{v:.4g}"), tail])


def answer_line(configfile: str, a, b, payload_kg: float | None, configuration: str | None, as_json: bool) -> str:
    """The text (or JSON) answer to ``query line`` (default payload: the config's largest task payload;
    default configuration: the arm's own at the task start)."""
    run, q = load_question(configfile)
    length = float(np.linalg.norm(np.subtract(b, a)))  # the pipeline's bounds on a verified line
    t_s = line_duration_s(length, run.task.v_max_mps, run.task.a_max_mps2)
    check_duration(t_s, "task.v_max_mps", "task.a_max_mps2", f"the queried line ({length:.3g} m)")
    check_steps(t_s / run.verification.dt_s, "verification.dt_s",
                f"verifying the queried line ({length:.3g} m) at verification.dt_s = {run.verification.dt_s:g} s")
    arm = q.dyn.arm
    payload = max(run.task.payload_kg) if payload_kg is None else float(payload_kg)
    q_ref = np.deg2rad(np.asarray(run.failure.q_start_deg, dtype=float))[arm.active]
    ans = line_query(q, a, b, payload, run.verification.dt_s, configuration, q_ref)
    v = ans.verdict
    row = {"configuration": ans.configuration, "payload_kg": payload, "length_m": v.length_m,
           "duration_s": v.duration_s, "capacity_kg": v.capacity_kg, "binding": v.binding,
           "margin_pct": v.min_margin_pct, "peak_load_pct": v.peak_load_pct, "peak_load": v.peak_load,
           "limits_exceeded_at_payload": v.limits_exceeded_at_payload or "none", "tracking": v.tracking,
           "joint_range": v.joint_range, "feasible": v.feasible,
           **{f"q_start_j{j}_deg": float(np.rad2deg(x)) for j, x in zip(arm.active_joint_numbers, ans.q_start_rad)}}
    if as_json:  # NaN (e.g. the margin over a 0 kg payload) as null
        clean = {k: None if isinstance(v, float) and not np.isfinite(v) else v for k, v in row.items()}
        return json.dumps({"a_m": list(map(float, a)), "b_m": list(map(float, b)), "run": run.name, **clean}, indent=1)
    w = max(map(len, row))
    lines = [f"capmap: run {run.name!r}, {run.failure.describe()}",
             f"line [{', '.join(f'{x:g}' for x in a)}] -> [{', '.join(f'{x:g}' for x in b)}] m carrying {payload:g} kg "
             f"on configuration {ans.configuration} (verified as the verify stage verifies a path):"]
    lines += [f"  {k:<{w}}  {val:.4g}" if isinstance(val, float) else f"  {k:<{w}}  {val}" for k, val in row.items()]
    return "\n".join(lines)
