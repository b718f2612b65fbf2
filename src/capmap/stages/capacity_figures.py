"""Figure-making stage of the capacity map: the summary table and the capacity-coloured workspace
(kept apart from the capacity stages so that those jobs do not import matplotlib)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.capacity.build import configuration_name
from capmap.capacity.tables import configuration_voxels
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_quantities
from capmap.plots.baseline import BaselineContext, baseline_figure
from capmap.plots.capacity import capacity_map
from capmap.plots.capacity_3d import PlannedPath, capacity_3d_html
from capmap.plots.palette import PATH_COLOURS
from capmap.robots import run_arm
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_summary", "stage_capacity_3d", "stage_baseline_figure", "MapView"]


@dataclass(frozen=True)
class MapView:
    """What the map's figures mark: the task's start and goal (3,) [m] and its payloads [kg]; the
    arm's configuration at the start (e.g. ``S+E-W+``)."""

    start_m: np.ndarray
    goal_m: np.ndarray
    payloads_kg: tuple[float, ...]
    configuration: str = ""

    @classmethod
    def from_slice(cls, slice_json: str) -> MapView:
        run = stage_config(slice_json).run
        return cls(np.asarray(run.failure.start_m, float), np.asarray(run.task.goal_m, float), run.task.payload_kg,
                   configuration_name(run_arm(run), run.failure.q_start_deg))


def _planned(waypoints: list[str]) -> tuple[list[tuple[float, float, np.ndarray, np.ndarray]], list[str]]:
    """Each payload's planned path: (payload kg, cost m, waypoints (n, 3) m, the capacity of the move
    arriving at each waypoint along its own direction, kg (NaN at the start)); the payloads without one."""
    paths, missing = [], []
    for wp in map(datasets.read, waypoints):
        meta = wp.attrs["capmap"]
        if meta["status"] == "ok":
            moves = wp.move_capacity_kg.to_numpy(float) if "move_capacity_kg" in wp else np.full(len(wp), np.nan)
            paths.append((meta["payload_kg"], meta["cost_m"], wp[["x_m", "y_m", "z_m"]].to_numpy(), moves))
        else:
            missing.append(f"{meta['payload_kg']:g} kg")
    return paths, missing


def _verdicts(verified: list[str] | None) -> dict:
    """The verification's rows by (payload kg, path: 'direct' / 'planned' / '<task>: planned')."""
    rows = pd.concat([pd.read_csv(f) for f in verified or []] or [pd.DataFrame(columns=["payload_kg", "path"])])
    return {(float(r.payload_kg), r.path): r for r in rows.itertuples()}


def _map_paths(view: MapView, waypoints: list[str], verified: list[str] | None) -> tuple[list[tuple], str]:
    """The summary figure's paths (label, (n, 3) m, style, the capacity of each of its pieces along its own
    direction kg or None): the direct line (its verified capacity) and each payload's planned path (its planned
    moves'), labelled with the verification's verdict (``verified``: the payloads' verify summary.csv files) or,
    without it, with its planned moves' least; and the paths' verdict in words for the headline."""
    ok = _verdicts(verified)
    rows = [(m, ok[(m, "direct")]) for m in view.payloads_kg if (m, "direct") in ok]
    label = "direct line" + (f": {rows[0][1].capacity_kg:,.0f} kg, " + ", ".join(
        f"{m:g} kg {'holds' if r.feasible else 'FAILS'}" for m, r in rows) if rows else "")
    paths = [(label, np.stack([view.start_m, view.goal_m]), {"color": "black"},
              np.array([rows[0][1].capacity_kg]) if rows else None)]
    planned, missing = _planned(waypoints)
    for n, (m, _, p, mv) in enumerate(planned):
        r = ok.get((m, "planned"))
        what = (f"{'holds' if r.feasible else 'FAILS'} ({r.capacity_kg:,.0f} kg)" if r is not None else
                f"moves ≥ {np.nanmin(mv):,.0f} kg (not verified)" if np.isfinite(mv).any() else "not verified")
        paths.append((f"A* plan for {m:g} kg: {what}", p, {"color": PATH_COLOURS[n % len(PATH_COLOURS)]}, mv[1:]))
    return paths, _paths_verdict(view, ok, missing)


def _paths_verdict(view: MapView, ok: dict, missing: list[str]) -> str:
    """The paths' verdict for the summary's headline, from the verification's rows ``ok``: the payloads that hold
    only on their plan, or on no path; those without a plan ('' when nothing of the kind)."""
    words = []
    for m in view.payloads_kg:
        d, q = ok.get((m, "direct")), ok.get((m, "planned"))
        if d is not None and q is not None and not d.feasible:
            words.append(f"{m:g} kg holds only on its A* plan" if q.feasible else f"{m:g} kg holds on no path")
    return "; ".join(words + [f"no plan for {', '.join(missing)}"] * bool(missing))


def _summary_rows(vox: pd.DataFrame, pts: pd.DataFrame, op: pd.DataFrame | None, configuration: str):
    """The summary table's rows (quantity, value), the reachable voxels and their median capacity (kg)."""
    reach_v = vox[vox.n_reachable > 0]
    reach_p = pts[pts.reachable]
    q = (reach_v.capacity_kg.quantile([0.0, 0.05, 0.5, 0.95, 1.0]) if len(reach_v)
         else pd.Series(np.nan, [0, .05, .5, .95, 1]))
    rows = [
        ("points evaluated", len(pts)), ("points reachable at task orientation", len(reach_p)),
        ("motion states evaluated", int(pts.n_states.sum())),
        ("voxels in grid", len(vox)), ("voxels without samples", int((vox.n_points == 0).sum())),
        ("reachable voxels", len(reach_v)),
        ("voxel capacity min [kg]", round(q.iloc[0], 1)), ("voxel capacity p5 [kg]", round(q.iloc[1], 1)),
        ("voxel capacity median [kg]", round(q.iloc[2], 1)), ("voxel capacity p95 [kg]", round(q.iloc[3], 1)),
        ("voxel capacity max [kg]", round(q.iloc[4], 1)),
    ]
    for name, count in reach_p.binding.astype(str).value_counts().items():
        rows.append((f"points bound by {name}", int(count)))
    if op is not None:
        r = op[op.n_reachable > 0]
        rows += [(f"voxels reached on the arm's configuration {configuration}", len(r)),
                 (f"voxel capacity median on {configuration} [kg]", round(float(r.capacity_kg.median()), 1)
                  if len(r) else np.nan),
                 (f"voxels of 0 kg on {configuration} (a singular surface crosses them)",
                  int((r.capacity_kg == 0).sum())),
                 ("voxels of 0 kg for any configuration", int((reach_v.capacity_kg == 0).sum()))]
    return rows, reach_v, q.iloc[2]


def stage_summary(voxels: str, configurations: str, points: str, waypoints: list[str], out: Outputs,
                  slice_json: str, verified: list[str] | None = None) -> None:
    """Capacity summary table (``out["csv"]``, ``out["md"]``) and the map figure (``out["png"]``: the arm's
    configuration and the bound for any, the direct line and the planned paths drawn with their verdicts
    from ``verified``, the payloads' verify summary.csv files, when given)."""
    vox, pts = datasets.read(voxels), datasets.read(points)
    view = MapView.from_slice(slice_json)
    op = configuration_voxels(vox, datasets.read(configurations), view.configuration)
    rows, reach_v, median = _summary_rows(vox, pts, op, view.configuration)
    write_quantities(rows, out["csv"], out["md"])
    capacity_map(vox, view, out["png"], op, view.configuration, *_map_paths(view, waypoints, verified))
    stage_logger(__name__, "summary").info(f"{len(reach_v)} reachable voxels, median capacity {median:.1f} kg "
                                           f"-> {out['csv']}, {out['png']}")


def _verified_3d(r, m: float) -> str:
    """A verified path's verdict for the 3D page's legend (e.g. 'verified: holds, weakest segment 4,149 kg
    (+3.7 %)'; where its tracking was lost)."""
    tracking = str(getattr(r, "tracking", "ok"))
    if tracking != "ok":
        return "verified: FAILS, " + tracking.split(":")[0].replace("failed", "tracking lost")
    return (f"verified: {'holds' if r.feasible else 'FAILS'}, weakest segment {r.capacity_kg:,.0f} kg "
            f"({100 * (r.capacity_kg / m - 1):+.1f} %)")


def _task_3d(name: str, path: str, ok: dict, arm) -> tuple[list[PlannedPath], list[str], str]:
    """A further task's paths for the 3D page (its planned path and direct line, in its legend group, with
    their verdicts from the verification's rows ``ok``), the payloads without a path and the configuration it
    starts on (from its plan's provenance; '' when not recorded)."""
    wp = datasets.read(path)
    q = wp.attrs["capmap"].get("config", {}).get("job", {}).get("q_start_deg")
    conf = configuration_name(arm, q) if q is not None else ""
    group = f"task {name}, on {conf}" if conf else f"task {name}"
    found, none = _planned([path])
    paths = []
    for m, cost, p, mv in found:
        r, d = ok.get((m, f"{name}: planned")), ok.get((m, f"{name}: direct"))
        paths += [PlannedPath(f"task {name}: planned path, {m:g} kg ({cost:.2f} m)", p, ends=name, moves_kg=mv,
                              verdict=_verified_3d(r, m) if r is not None else "", group=group),
                  PlannedPath(f"{name}: direct line", p[[0, -1]], ends=name, group=group, direct=True,
                              verdict=_verified_3d(d, m) if d is not None else "")]
    return paths, [f"task {name} ({m})" for m in none], conf


def _main_3d(view: MapView, waypoints: list[str], ok: dict) -> tuple[list[PlannedPath], list[str]]:
    """The main task's paths for the 3D page (its direct line with its verdicts at every payload, each payload's
    planned path with its own) and the payloads without a plan."""
    planned, missing = _planned(waypoints)
    rows = [(m, ok[(m, "direct")]) for m in view.payloads_kg if (m, "direct") in ok]
    group = f"main task, on {view.configuration}" if view.configuration else "main task"
    direct = [PlannedPath("direct line", np.stack([view.start_m, view.goal_m]), group=group, direct=True,
                          verdict=(f"verified: {', '.join(f'{m:g} kg ' + ('holds' if r.feasible else 'FAILS') for m, r in rows)}"
                                   f" ({rows[0][1].capacity_kg:,.0f} kg)") if rows else "")]
    return direct + [PlannedPath(f"planned path, {m:g} kg ({cost:.2f} m)", p, moves_kg=mv, group=group,
                                 verdict=_verified_3d(ok[(m, "planned")], m) if (m, "planned") in ok else "")
                     for m, cost, p, mv in planned], missing


def _maps_3d(vox: pd.DataFrame, conf: pd.DataFrame, shown: dict[str, str]) -> list[tuple[str, str, pd.DataFrame]]:
    """The 3D page's maps (configuration, button label, reached voxels): each configuration of ``shown`` (name ->
    whose) that has a map, then the bound for any configuration (configuration '')."""
    maps = [(c, f"configuration {c} ({who})", configuration_voxels(vox, conf, c)) for c, who in shown.items() if c]
    return [(c, n, m[m.n_reachable > 0]) for c, n, m in maps if m is not None] + [
        ("", "any configuration (the bound: every IK branch)", vox[vox.n_reachable > 0])]


def _title_3d(maps: list[tuple], payload_kg: float, paths: list[PlannedPath], missing: list[str]) -> str:
    """The 3D page's headline, one line: the share of the first map's voxels carrying the first payload, how
    many verified planned paths hold, the paths missing."""
    c = maps[0][2].capacity_kg.to_numpy()
    verdicts = [p.verdict for p in paths if not p.direct and p.verdict]
    held = sum(v.startswith("verified: holds") for v in verdicts)
    return (f"{maps[0][1][0].upper() + maps[0][1][1:]}: {100 * np.mean(c >= payload_kg) if len(c) else 0:.0f} % of "
            f"the reachable voxels carry {payload_kg:g} kg"
            + (f"; {'every' if held == len(verdicts) else f'{held} of {len(verdicts)}'} verified planned path"
               f"{'' if held == len(verdicts) else 's'} hold{'s' if held == len(verdicts) else ''}" if verdicts else "")
            + (f"; no path for {', '.join(missing)}" if missing else ""))


def stage_capacity_3d(voxels: str, configurations: str, waypoints: list[str], out_html: str, slice_json: str,
                      task_waypoints: dict[str, str] | None = None, verified: list[str] | None = None) -> None:
    """The interactive 3D view (self-contained HTML): reachable voxels by capacity on the arm's configuration
    (buttons: the map of each further task's start configuration, the bound for any configuration), a payload
    slider, the direct line, each payload's planned path and each further task's (``task_waypoints``: name ->
    its waypoints; a missing path is named in the title), start and goal, each shown on the map it was planned
    on and on the bound; each path's verdict from ``verified`` (the verify summary.csv files of the payloads and
    tasks; without them, its planned moves' least)."""
    vox, conf = datasets.read(voxels), datasets.read(configurations)
    view = MapView.from_slice(slice_json)
    ok = _verdicts(verified)
    paths, missing = _main_3d(view, waypoints, ok)
    arm = run_arm(stage_config(slice_json).run) if task_waypoints else None
    tasks = [_task_3d(name, path, ok, arm) for name, path in (task_waypoints or {}).items()]
    maps = _maps_3d(vox, conf, {view.configuration: "the main task's"} | {
        c: f"task {n}'s" for n, (_, _, c) in zip(task_waypoints or {}, tasks) if c and c != view.configuration})
    at = {c: (n, len(maps) - 1) for n, (c, *_) in enumerate(maps[:-1])}
    paths = [replace(p, on_map=at.get(view.configuration)) for p in paths] + [
        replace(p, on_map=at.get(c)) for ps, _, c in tasks for p in ps]
    missing += [m for t in tasks for m in t[1]]
    html = capacity_3d_html([(name, m[["x_m", "y_m", "z_m"]].to_numpy(), m.capacity_kg.to_numpy(),
                              m.binding.astype(str).to_numpy()) for _, name, m in maps],
                            vox.attrs["capmap"]["grid"]["edge_m"], view.start_m, view.goal_m, paths, view.payloads_kg,
                            _title_3d(maps, view.payloads_kg[0] if view.payloads_kg else 0.0, paths, missing))
    Path(out_html).parent.mkdir(parents=True, exist_ok=True)
    Path(out_html).write_text(html)
    stage_logger(__name__, "capacity 3d").info(f"{', '.join(f'{n}: {len(m)} voxels' for _, n, m in maps)}, "
                                               f"{len(paths)} paths -> {out_html} ({len(html) / 1e6:.1f} MB, offline)")


def stage_baseline_figure(voxels: str, convergence: str, out_png: str, slice_json: str) -> None:
    """The baseline's figure (:func:`capmap.plots.baseline.baseline_figure`)."""
    df, conv = datasets.read(voxels), datasets.read(convergence)
    view = MapView.from_slice(slice_json)
    run = stage_config(slice_json).run
    meta = df.attrs["capmap"]
    context = BaselineContext(meta["configuration"], run.failure.joint, run.failure.angle_deg,
                              conv.attrs["capmap"]["step_deg"], conv.attrs["capmap"]["check_step_deg"],
                              meta["grid"]["edge_m"], view.start_m, view.payloads_kg)
    baseline_figure(df, conv, context, out_png)
    stage_logger(__name__, "baseline figure").info(f"-> {out_png}")
