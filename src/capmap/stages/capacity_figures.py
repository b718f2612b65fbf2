"""Figure-making stage of the capacity map: the summary table and the capacity-coloured workspace
(kept apart from the capacity stages so that those jobs do not import matplotlib)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_quantities
from capmap.plots.capacity import capacity_map

__all__ = ["stage_summary"]


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
    capacity_map(vox, out_png)
    stage_logger(__name__, "summary").info(f"{len(reach_v)} reachable voxels, median capacity {q.iloc[2]:.1f} kg "
                                           f"-> {out_csv}, {out_png}")
