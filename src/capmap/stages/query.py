"""``python -m capmap query``: a run's config in, a question answered (:mod:`capmap.capacity.query`)
and the run's voxel values at the point, as a printed table or JSON. Reads the config as the
workflow checks it and, when they are of that config, the run's voxel maps."""

from __future__ import annotations

import json
import sys
import textwrap
from pathlib import Path

import numpy as np

from capmap.capacity.build import capacity_problem
from capmap.capacity.engine import margin_pct
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.query import line_query, point_query
from capmap.capacity.voxels import Grid
from capmap.checks import check_capacity_config
from capmap.config.estimate import check_duration, check_steps, line_duration_s
from capmap.config.run import RunConfig, run_document
from capmap.config.slices import stage_slice
from capmap.errors import CapmapError
from capmap.io.arrays import read_columns
from capmap.io.datasets import canonical
from capmap.io.kernel_marker import is_warm, record, run_key

__all__ = ["load_question", "answer", "answer_point", "answer_line"]

def answer(request: dict) -> tuple[int, str, str]:
    """A ``capmap query`` question (``what``: point or line, ``configfile``, ``payload_kg``, ``json``; a point:
    ``point_m``, ``joints``; a line: ``a_m``, ``b_m``, ``configuration``) answered: (exit status, the text
    for stdout, the one line for stderr). A compile's announcement goes to stderr as it starts."""
    m = request.get("payload_kg")
    try:
        if m is not None and not (m >= 0 and m < float("inf")):
            raise CapmapError(f"--payload {m} must be a finite mass >= 0 kg")
        if request["what"] == "point":
            text = answer_point(request["configfile"], request["point_m"], m, request["json"],
                                joints=request.get("joints", False))
        else:
            text = answer_line(request["configfile"], request["a_m"], request["b_m"], m,
                               request.get("configuration"), request["json"])
    except CapmapError as exc:
        return 1, "", f"capmap: {exc}\n"
    return 0, text + "\n", ""


def load_question(configfile: str) -> tuple[RunConfig, CapacityProblem]:
    """The run config of ``configfile`` with its capacity part checked (as the workflow checks it) and the
    capacity problem it asks about (per configuration)."""
    run = check_capacity_config(run_document([configfile]), configfile)
    problem = capacity_problem(run, per_configuration=True)
    key = run_key(run.robot, run.failure.joint, float(np.deg2rad(run.failure.angle_deg)), False,
                  len(run.failure.q_start_deg))
    if not any(is_warm(k) for k in (key, f"{key} dualarm", f"{key} query")):
        print(f"capmap: compiling the kernels a query of {Path(run.robot).name} with joint {run.failure.joint} locked needs: "
              "once per machine and code version (about a minute on 2 cores)...", file=sys.stderr, flush=True)
        point_query(problem, np.asarray(run.failure.start_m, dtype=float))  # the start: reached by construction
        record(f"{key} query")
    return run, problem


BOUNDARY_M = 1e-6
"""A point this close to a voxel face is on it: it is answered with every voxel it touches (their least)."""


def _run_voxels(run: RunConfig, results: Path, point: np.ndarray) -> dict:
    """The run's voxel values at the point: {"voxels": [(i, j, k), ...] the voxels it touches (one inside a
    voxel, up to eight on a corner), "map_kg": the least all-branch value over them, "configurations":
    {name: least kg}, "note": why there are none}."""
    base = results / run.name / "voxels"
    path, conf_path = base / "voxels.parquet", base / "configurations.parquet"
    if not path.is_file():
        return {"note": f"no voxel map at {path} (run: capmap run, or snakemake --cores 2 capacity_map)"}
    try:
        vox, meta = read_columns(path, ["n_reachable", "capacity_kg"])
        have = {k: v for k, v in meta["config"].items() if k != "code"}
        g = meta["grid"]
        grid = Grid(np.asarray(g["lower_m"], dtype=float), tuple(g["shape"]), float(g["edge_m"]))
    except (CapmapError, KeyError, TypeError, AttributeError) as exc:
        return {"note": f"{path} is not a voxel map capmap wrote ({exc}); rerun: snakemake --cores 2 capacity_map"}
    want = {k: v for k, v in stage_slice(run, "refine").items() if k != "code"}
    if canonical(want) != canonical(have):
        return {"note": f"{path} is of another config than this one (rerun: snakemake --cores 2 capacity_map)"}
    idx = grid.touching(point, BOUNDARY_M)
    if not len(idx):
        return {"note": "outside the run's voxel grid"}
    flat = grid.flat(idx)
    cap = vox["capacity_kg"][flat]
    cap = cap[(vox["n_reachable"][flat] > 0) & np.isfinite(cap)]
    out = {"voxels": idx.tolist(), "map_kg": float(cap.min()) if len(cap) else None, "configurations": {}}  # JSON null
    if conf_path.is_file():
        conf, _ = read_columns(conf_path, ["i", "j", "k", "configuration", "capacity_kg"])
        ijk = np.stack([conf["i"], conf["j"], conf["k"]], axis=1).astype(np.int64).reshape(-1, 3)
        mine = np.isin(grid.flat(ijk), flat) & np.isfinite(conf["capacity_kg"].astype(float))
        for c, v in zip(conf["configuration"][mine], conf["capacity_kg"][mine]):
            out["configurations"][str(c)] = min(float(v), out["configurations"].get(str(c), np.inf))
    return out


def _arm_configuration(run: RunConfig, q: CapacityProblem) -> str:
    """The configuration the arm holds at the task start (of task.q_ini_deg / the start configuration)."""
    q_ref = np.deg2rad(np.asarray(run.failure.q_start_deg, dtype=float))[q.dyn.arm.active]
    return q.labels.names[int(q.labels.labels(q_ref[None])[0])]


def _verdict(ans, arm_cfg: str, payload_kg: float) -> dict:
    """Whether the arm's configuration (and any) carries the payload at the point."""
    cap = np.asarray(ans.capacity_kg)
    mine = cap[[c == arm_cfg for c in ans.configuration]]
    best = int(np.argmax(cap))
    return {"payload_kg": payload_kg, "arm_configuration": arm_cfg,
            "arm_reaches": bool(len(mine)), "arm_capacity_kg": float(mine.min()) if len(mine) else None,
            "arm_carries": bool(len(mine) and mine.min() >= payload_kg),
            "arm_margin_pct": float(margin_pct(mine.min(), payload_kg)) if len(mine) else None,
            "configurations_carrying": sorted({c for c, v in zip(ans.configuration, cap) if v >= payload_kg}),
            "best_configuration": ans.configuration[best], "best_capacity_kg": float(cap[best])}


def _verdict_line(v: dict, n_conf: int) -> str:
    m, c = v["payload_kg"], v["arm_configuration"]
    n = len(v["configurations_carrying"])
    if not v["arm_reaches"]:
        return (f"verdict: the arm's configuration {c} does not reach this point; {n} of {n_conf} configurations "
                f"carry {m:g} kg (the best: {v['best_capacity_kg']:.0f} kg on {v['best_configuration']})")
    return (f"verdict: carries {m:g} kg on {c}, the arm's: {'yes' if v['arm_carries'] else 'NO'}, margin "
            f"{v['arm_margin_pct']:.0f} %; {n} of {n_conf} configurations carry it")


def answer_point(configfile: str, point, payload_kg: float | None, as_json: bool, results: str = "results",
                 joints: bool = False) -> str:
    """The text (or JSON) answer to ``query point``: every IK branch's capacity at the point, the arm's
    configuration marked, the verdict for ``payload_kg``, the run's voxel values there (``joints``: the
    branches' joint angles too; always in the JSON)."""
    run, q = load_question(configfile)
    p = np.asarray(point, dtype=float)
    ans = point_query(q, p)
    vox = _run_voxels(run, Path(results), p)
    arm_cfg = _arm_configuration(run, q)
    voxel_cfg = vox.get("configurations", {})
    names = q.dyn.arm.active_joint_numbers
    verdict = None if payload_kg is None else _verdict(ans, arm_cfg, payload_kg)
    if as_json:
        branches = [{"configuration": c, "arms": c == arm_cfg, "capacity_kg": float(k), "binding": b,
                     "worst_direction": [float(x) for x in np.round(u, 6) + 0.0], "voxel_capacity_kg": voxel_cfg.get(c),
                     **({"margin_pct": float(margin_pct(k, payload_kg))} if payload_kg is not None else {}),
                     **{f"q_j{j}_deg": float(np.rad2deg(x)) for j, x in zip(names, qq)}}
                    for c, k, b, u, qq in zip(ans.configuration, ans.capacity_kg, ans.binding, ans.worst_u, ans.q_rad)]
        return json.dumps({"point_m": p.tolist(), "run": run.name, "lock": run.failure.describe(),
                           "arm_configuration": arm_cfg, "verdict": verdict, "voxel": vox, "branches": branches},
                          indent=1)
    head = [f"capmap: run {run.name!r}: {run.failure.describe().split(';')[0]}",
            f"point [{', '.join(f'{v:g}' for v in p)}] m at the task orientation: {len(ans.configuration)} IK branches "
            f"on {len(set(ans.configuration))} configurations"]
    rows = [_row(c, k, b, u, voxel_cfg.get(c), payload_kg, c == arm_cfg)
            for c, k, b, u in zip(ans.configuration, ans.capacity_kg, ans.binding, ans.worst_u)]
    table = [_HEADER if payload_kg is not None else _HEADER.replace("margin_pct", "          ")] + rows
    if joints:
        table += ["", "config   " + "".join(f"{f'q_j{j}_deg':>10}" for j in names)]
        table += [f"{c:<9}" + "".join(f"{np.rad2deg(x):10.2f}" for x in qq) for c, qq in zip(ans.configuration, ans.q_rad)]
    tail = [f"* the arm's configuration ({arm_cfg}: the one it holds at the task start); "
            f"{q.labels.description.split(';')[0]}"]
    if verdict is not None:
        tail.append(_verdict_line(verdict, len(q.labels.names)))
    tail.append(_voxel_line(vox))
    return "\n".join(_wrap(head) + [r.rstrip() for r in table] + _wrap(tail))


_HEADER = "config      capacity_kg  margin_pct  binding      worst direction (x, y, z)  voxel_kg"


def _row(conf: str, cap: float, binding: str, u, voxel_kg, payload_kg, mine: bool) -> str:
    direction = "(" + ", ".join(f"{v + 0.0:+.3f}" for v in u) + ")"
    margin = f"{margin_pct(cap, payload_kg):10.1f}" if payload_kg is not None else " " * 10
    vk = "—" if voxel_kg is None else f"{voxel_kg:.0f}"
    return f"{conf + (' *' if mine else ''):<10}{cap:12.0f}  {margin}  {binding:<12} {direction:<26} {vk:>8}"


def _voxel_line(vox: dict) -> str:
    if "note" in vox:
        return f"run's voxel map: {vox['note']}"
    where = (f"voxel {tuple(vox['voxels'][0])}" if len(vox["voxels"]) == 1 else
             f"on the boundary of {len(vox['voxels'])} voxels {', '.join(str(tuple(v)) for v in vox['voxels'])}: the least")
    bound = "no sampled point reached" if vox["map_kg"] is None else f"{vox['map_kg']:.1f} kg"
    return (f"run's map: {where}: {bound} for any configuration; voxel_kg: each configuration's least over the voxel "
            "(the map holds over the whole voxel and every motion direction)")


def _wrap(lines: list[str], width: int = 100) -> list[str]:
    return [w for ln in lines for w in textwrap.wrap(ln, width, subsequent_indent="  ", break_on_hyphens=False)]


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
    head = [f"capmap: run {run.name!r}: {run.failure.describe().split(';')[0]}",
            f"line [{', '.join(f'{x:g}' for x in a)}] -> [{', '.join(f'{x:g}' for x in b)}] m carrying {payload:g} kg "
            f"on configuration {ans.configuration} (verified as the verify stage verifies a path):"]
    lines = [f"  {k:<{w}}  {val:.4g}" if isinstance(val, float) else f"  {k:<{w}}  {val}" for k, val in row.items()]
    mine = "the arm's" if configuration is None else "the one asked"
    reasons = [f"exceeds {v.limits_exceeded_at_payload}" if v.limits_exceeded_at_payload else "",
               "" if v.tracking == "ok" else f"tracking: {v.tracking}",
               "" if v.joint_range == "ok" else f"joint range: {v.joint_range}"]
    why = "" if v.feasible else f" ({'; '.join(r for r in reasons if r)})"
    verdict = (f"verdict: the line carries {payload:g} kg on {ans.configuration}, {mine}: "
               f"{'yes' if v.feasible else 'NO'}, margin {v.min_margin_pct:.0f} %{why}")
    return "\n".join(_wrap(head) + lines + _wrap([verdict]))
