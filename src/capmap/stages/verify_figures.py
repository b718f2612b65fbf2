"""Figures of the verified motions (kept apart so that the planning and verification jobs do not
import matplotlib)."""

from __future__ import annotations

from capmap.capacity.build import configuration_name, run_arm
from capmap.capacity.tables import configuration_voxels
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.capacity import load_series, workspace_paths
from capmap.stages.common import stage_config

__all__ = ["stage_verify_plots"]


def stage_verify_plots(voxels: str, configurations: str, timeseries: str, out_workspace: str, out_torques: str,
                       out_force: str, out_moment: str, slice_json: str) -> None:
    """Capacity workspace with both paths on the map of the start's configuration; torques, base force and
    base moment against their limits."""
    vox, ts = datasets.read(voxels), datasets.read(timeseries)
    sc = stage_config(slice_json)
    name = configuration_name(run_arm(sc.run), sc.job.q_start_deg)
    op = configuration_voxels(vox, datasets.read(configurations), name)
    meta = ts.attrs["capmap"]
    payload, limits = meta["payload_kg"], meta["limits"]
    no_path = "" if meta.get("plan_status", "ok") == "ok" else meta.get("plan_reason", "")
    workspace_paths(vox, ts, payload, out_workspace, no_path, op, name)
    for prefix, what, out in (("tau_", "Joint torques", out_torques), ("base_f", "Base disturbance force", out_force),
                              ("base_m", "Base disturbance moment", out_moment)):
        load_series(ts, [c for c in limits if c.startswith(prefix)], limits, f"{what} carrying {payload:g} kg", out)
    stage_logger(__name__, f"verify plots {payload:g} kg").info(f"-> {out_workspace}, {out_torques}, {out_force}, "
                                                                f"{out_moment}")
