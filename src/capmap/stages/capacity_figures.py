"""Figure-making stage of the capacity map: the summary table and the capacity-coloured workspace
(kept apart from the capacity stages so that those jobs do not import matplotlib)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_quantities
from capmap.plots.capacity import capacity_map
from capmap.plots.capacity_3d import PlannedPath, capacity_3d_html
from capmap.stages.common import stage_config

__all__ = ["stage_summary", "stage_capacity_3d", "MapView"]


@dataclass(frozen=True)
class MapView:
    """What the map's figures mark: the task's start and goal (3,) [m] and its payloads [kg]."""

    start_m: np.ndarray
    goal_m: np.ndarray
    payloads_kg: tuple[float, ...]

    @classmethod
    def from_slice(cls, slice_json: str) -> MapView:
        run = stage_config(slice_json).run
        return cls(np.asarray(run.failure.start_m, float), np.asarray(run.task.goal_m, float), run.task.payload_kg)


def stage_summary(voxels: str, points: str, out_csv: str, out_md: str, out_png: str, slice_json: str) -> None:
    """Capacity summary table (CSV + Markdown) and a capacity-coloured workspace figure."""
    vox, pts = datasets.read(voxels), datasets.read(points)
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
    write_quantities(rows, out_csv, out_md)
    capacity_map(vox, MapView.from_slice(slice_json), out_png)
    stage_logger(__name__, "summary").info(f"{len(reach_v)} reachable voxels, median capacity {q.iloc[2]:.1f} kg "
                                           f"-> {out_csv}, {out_png}")


def stage_capacity_3d(voxels: str, waypoints: list[str], out_html: str, slice_json: str) -> None:
    """The interactive 3D view (self-contained HTML): reachable voxels by capacity, a payload slider,
    the direct line, each payload's planned path (or its absence, in the title), start and goal."""
    vox = datasets.read(voxels)
    view = MapView.from_slice(slice_json)
    reach = vox[vox.n_reachable > 0]
    paths, missing = [], []
    for wp in map(datasets.read, waypoints):
        meta = wp.attrs["capmap"]
        if meta["status"] == "ok":
            paths.append(PlannedPath(f"planned path, {meta['payload_kg']:g} kg ({meta['cost_m']:.2f} m)",
                                     wp[["x_m", "y_m", "z_m"]].to_numpy()))
        else:
            missing.append(f"{meta['payload_kg']:g} kg")
    edge = vox.attrs["capmap"]["grid"]["edge_m"]
    title = "Capacity map: reachable voxels by dynamic load-carrying capacity" + (
        f"; no path for {', '.join(missing)}" if missing else "")
    html = capacity_3d_html(reach[["x_m", "y_m", "z_m"]].to_numpy(), reach.capacity_kg.to_numpy(), edge,
                            view.start_m, view.goal_m, paths, view.payloads_kg, title)
    Path(out_html).parent.mkdir(parents=True, exist_ok=True)
    Path(out_html).write_text(html)
    stage_logger(__name__, "capacity 3d").info(f"{len(reach)} voxels, {len(paths)} planned paths -> {out_html} "
                                               f"({len(html) / 1e6:.1f} MB, offline)")
