"""Figures of the verified motions (kept apart so that the planning and verification jobs do not
import matplotlib)."""

from __future__ import annotations

from capmap.capacity.build import configuration_name
from capmap.capacity.tables import configuration_voxels
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.capacity import load_series, workspace_paths
from capmap.robots import run_arm
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_verify_plots"]


def stage_verify_plots(voxels: str, configurations: str, timeseries: str, out: Outputs, slice_json: str) -> None:
    """Capacity workspace with both paths on the map of the start's configuration (``out["workspace"]``);
    torques, base force and base moment against their limits (``torques``, ``force``, ``moment``)."""
    vox, ts = datasets.read(voxels), datasets.read(timeseries)
    sc = stage_config(slice_json)
    name = configuration_name(run_arm(sc.run), sc.job.q_start_deg)
    op = configuration_voxels(vox, datasets.read(configurations), name)
    meta = ts.attrs["capmap"]
    payload, limits = meta["payload_kg"], meta["limits"]
    no_path = "" if meta.get("plan_status", "ok") == "ok" else meta.get("plan_reason", "")
    workspace_paths(vox, ts, payload, out["workspace"], no_path, op, name)
    for prefix, what, key in (("tau_", "Joint torques", "torques"), ("base_f", "Base disturbance force", "force"),
                              ("base_m", "Base disturbance moment", "moment")):
        load_series(ts, [c for c in limits if c.startswith(prefix)], limits, f"{what} carrying {payload:g} kg", out[key])
    stage_logger(__name__, f"verify plots {payload:g} kg").info("-> " + ", ".join(out.values()))
