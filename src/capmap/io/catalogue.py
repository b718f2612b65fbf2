"""What every dataset of a run is, in one place: its catalogue name, what one row is and a description
(:data:`DATASETS`); the catalogue table a run writes (:func:`catalogue_table`); and the small API for
reading a run's results in pandas (:func:`catalogue`, :func:`load`).

docs/outputs.md's dataset table is generated from :data:`DATASETS`
(``python -m capmap.io.catalogue --write docs/outputs.md``; a test checks it is current)."""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from capmap.errors import DataError
from capmap.io.datasets import column_unit, read
from capmap.io.fingerprint import file_sha256

__all__ = ["DatasetDoc", "DATASETS", "describe", "catalogue_table", "catalogue", "load", "outputs_table"]


@dataclass(frozen=True)
class DatasetDoc:
    """A kind of dataset: ``pattern`` its path under the run folder (``{x}``: one path part),
    ``name`` its catalogue name (the same placeholders), ``row`` what one row is, ``description``."""

    pattern: str
    name: str
    row: str
    description: str

    def match(self, path: str | Path) -> str | None:
        """This kind's catalogue name of ``path`` (matched at its end), or None."""
        parts = re.split(r"(\{\w+\})", self.pattern)
        rx = "".join(f"(?P<{p[1:-1]}>[^/]+)" if p.startswith("{") else re.escape(p) for p in parts)
        m = re.search(f"(?:^|/){rx}$", Path(path).as_posix())
        return None if m is None else self.name.format(**m.groupdict())


DATASETS = (
    DatasetDoc("model/joints.parquet", "joints", "joint of the robot",
               "The robot model: joint limits, placements, link masses and inertias, drives (rotor inertia, friction)."),
    DatasetDoc("capacity/points.parquet", "points", "sampled point",
               "Each sampled point's capacity: the least over its IK branches and every motion direction, the "
               "limit that binds, the worst direction and configuration, the capacity along the 13 grid axes."),
    DatasetDoc("voxels/voxels.parquet", "voxels", "voxel of the grid",
               "The capacity map: each voxel's least capacity over its points, IK branches and every motion "
               "direction, refined until it converged (capacity_sampled_kg: over the sampled points alone); "
               "`reachable` False: no point of the voxel is reached (capacity NaN), keep the others with "
               "vox[vox.reachable]."),
    DatasetDoc("voxels/configurations.parquet", "configurations", "voxel x arm configuration reaching it",
               "The map per arm configuration (shoulder/elbow/wrist branch): each voxel's least capacity on it."),
    DatasetDoc("plan/payload_{payload}kg/waypoints.parquet", "plan_{payload}kg", "waypoint",
               "The A* path planned through the voxels that carry the payload (status no_path: none does)."),
    DatasetDoc("verify/payload_{payload}kg/timeseries.parquet", "verify_{payload}kg", "time sample of a path",
               "The direct line and the planned path simulated with the payload: joint torques, base force and "
               "moment, the capacity of each state."),
    DatasetDoc("verify/payload_{payload}kg/segments.parquet", "verify_{payload}kg_segments", "segment of a path",
               "Each segment of the verified paths: its capacity, margin and peak load against the limits."),
    DatasetDoc("tasks/{task}/waypoints.parquet", "task_{task}_plan", "waypoint",
               "A further task's planned path (as a payload's plan)."),
    DatasetDoc("tasks/{task}/timeseries.parquet", "task_{task}_verify", "time sample of a path",
               "A further task's direct line and planned path simulated (as a payload's verification)."),
    DatasetDoc("tasks/{task}/segments.parquet", "task_{task}_segments", "segment of a path",
               "A further task's verified segments (as a payload's)."),
    DatasetDoc("follow/{case}/timeseries.parquet", "follow_{case}", "stored control period",
               "The torque-limited follower on the case's path: commanded and followed path coordinate, joint "
               "torques against the limits, lag and deviation."),
    DatasetDoc("follow/{case}/toppra.parquet", "follow_{case}_toppra", "stored control period",
               "TOPP-RA's time-optimal profile on the same path (the reference the follower is compared with)."),
    DatasetDoc("reconfig/{method}.parquet", "reconfig_{method}", "integration step",
               "The booms' reconfiguration through the closed chain by this method: joint angles and rates, "
               "manipulability, closure and task errors."),
    DatasetDoc("dualarm/cloud.parquet", "dualarm_cloud", "scan point",
               "The cabin's point cloud (scanned or the user's), with the viewpoint that saw each point."),
    DatasetDoc("dualarm/environment.parquet", "dualarm_environment", "fitted volume",
               "Swept-sphere volumes (triangles, capsules) that cover every cloud point."),
    DatasetDoc("dualarm/unknown.parquet", "dualarm_unknown", "box of unknown space",
               "Space no viewpoint observed, treated as occupied."),
    DatasetDoc("dualarm/robot_capsules.parquet", "dualarm_capsules", "capsule",
               "The capsules that cover the two arms' links."),
    DatasetDoc("dualarm/trajectory.parquet", "dualarm_trajectory", "node of the motion",
               "The dual-arm motion: joint angles, rates and accelerations, closed-chain and path errors, "
               "the least distance to the cabin."),
    DatasetDoc("dualarm/fine.parquet", "dualarm_fine", "sample of the fine check grid",
               "The least distance to the cabin checked on a grid finer than the solver's."),
    DatasetDoc("dualarm/outer.parquet", "dualarm_solver", "outer iteration",
               "The augmented-Lagrangian solver's iterations: penalty, cost, constraint violations."),
    DatasetDoc("dualarm/torques.parquet", "dualarm_torques", "node of the motion",
               "Joint torques holding the panel (least-norm and peak-minimising internal force)."),
    DatasetDoc("atlas/joint{j}_angle{a}/voxels.parquet", "atlas_joint{j}_angle{a}", "voxel of the grid",
               "A coarse capacity map with joint {j} locked at {a} deg (as the voxels dataset)."),
    DatasetDoc("atlas/joint{j}_angle{a}/summary.parquet", "atlas_joint{j}_angle{a}_tasks", "task payload",
               "The task's verdicts with joint {j} locked at {a} deg."),
    DatasetDoc("atlas/atlas.parquet", "atlas", "joint x lock angle x payload",
               "The fault atlas: what each joint locked at each angle leaves for the task."),
    DatasetDoc("atlas/curves.parquet", "atlas_curves", "point of a curve",
               "The share of the workspace carrying each payload, per joint and lock angle."),
    DatasetDoc("baseline/voxels.parquet", "baseline", "voxel of the grid",
               "The healthy arm's capacity at the failed map's voxels, and what the failure cost."),
    DatasetDoc("baseline/healthy_{k}_of_{n}.parquet", "baseline_shard_{k}_of_{n}", "voxel of shard {k}",
               "The healthy arm's refined values on shard {k} of {n} (kept: the angle sweep is the costly part)."),
    DatasetDoc("baseline/convergence.parquet", "baseline_convergence", "checked point",
               "The healthy arm's capacity against a 1 deg sweep at random points (its convergence check)."),
    DatasetDoc("advice/sweeps/joint{j}.parquet", "lock_sweep_joint{j}", "lock angle x voxel",
               "The capacity maps of the arm with joint {j} locked at each angle of its sweep (one grid for every lock)."),
    DatasetDoc("advice/joint{j}/tasks.parquet", "advice_joint{j}_tasks", "lock angle x task",
               "Every task verified with joint {j} locked at each swept angle: paths, capacity, margin."),
    DatasetDoc("advice/joint{j}/healthy.parquet", "advice_joint{j}_healthy", "task",
               "The healthy arm's map along each task's direct line (the advice's reference)."),
    DatasetDoc("advice/joint{j}/advice.parquet", "advice_joint{j}", "joint",
               "Where to brake joint {j}: the angle with the largest worst-task margin."),
    DatasetDoc("advice/joint{j}/convergence.parquet", "advice_joint{j}_convergence", "angle step",
               "The recommendation for joint {j} on sweeps of 4, 2 and 1 times the step."),
    DatasetDoc("advice/tolerant.parquet", "tolerant", "voxel of the grid",
               "The failure-tolerant map: the capacity left whichever joint fails at whichever swept angle."),
    DatasetDoc("advice/tolerant_summary.parquet", "tolerant_summary", "task payload",
               "The volume carrying each payload, healthy and under any single failure."),
    DatasetDoc("plan/gain_tasks.parquet", "plan_gain", "random task",
               "Isotropic vs direction-aware A* on random tasks: found paths and their verified capacities."),
)
"""Every kind of dataset a run writes, most specific pattern first."""


def describe(path: str | Path) -> tuple[str, DatasetDoc]:
    """The catalogue name and the kind of a dataset's path; raises :class:`DataError` for a path of
    no known kind (a dataset added without its description)."""
    for doc in DATASETS:
        name = doc.match(path)
        if name is not None:
            return name, doc
    raise DataError(f"{path}: no entry in capmap.io.catalogue.DATASETS (add its name, row and description)")


def catalogue_table(paths: list[str | Path]) -> pd.DataFrame:
    """One row per dataset: ``name`` (unique), ``description``, ``row`` (what one row is), ``path``,
    ``stage``, ``rows``, ``columns`` (each with its unit), ``units`` (the units used), ``sha256``,
    ``config_hash``, ``capmap_version``. Raises :class:`DataError` when two paths share a name."""
    rows = []
    for p in paths:
        df = read(p)
        meta = df.attrs.get("capmap", {})
        name, doc = describe(p)
        fields = re.search(doc.name.replace("{", "(?P<").replace("}", ">.+)") + "$", name)
        units = sorted({column_unit(c) for c in df.columns} - {""})
        rows.append({"name": name, "description": doc.description.format(**(fields.groupdict() if fields else {})),
                     "row": doc.row, "path": str(p), "stage": meta.get("stage", ""), "rows": len(df),
                     "columns": [f"{c} [{column_unit(c)}]" if column_unit(c) else c for c in df.columns],
                     "units": ", ".join(units), "sha256": file_sha256(p), "config_hash": meta.get("config_hash", ""),
                     "capmap_version": meta.get("capmap_version", "")})
    cat = pd.DataFrame(rows)
    twice = cat.name[cat.name.duplicated()].tolist() if len(cat) else []
    if twice:
        raise DataError(f"catalogue names used twice: {', '.join(twice)}")
    return cat


def _run_folder(run: str | Path, results: str | Path) -> Path:
    folder = Path(run) if Path(run).is_dir() and (Path(run) / "catalogue.parquet").is_file() else Path(results) / run
    if not (folder / "catalogue.parquet").is_file():
        raise DataError(f"{folder}: no catalogue.parquet (run the workflow first: capmap run <config>)")
    return folder


def catalogue(run: str | Path = "default", results: str | Path = "results") -> pd.DataFrame:
    """The catalogue of a run (``results/<run>/catalogue.parquet``, or ``run`` a run folder): one row per
    dataset with its name, description, what a row is, path, rows, columns and units."""
    return read(_run_folder(run, results) / "catalogue.parquet")


def load(run: str | Path = "default", name: str = "voxels", results: str | Path = "results") -> pd.DataFrame:
    """The dataset ``name`` (a catalogue name, see :func:`catalogue`) of a run, with its provenance in
    ``df.attrs["capmap"]``. Raises :class:`DataError` naming the datasets there are."""
    folder = _run_folder(run, results)
    cat = read(folder / "catalogue.parquet")
    hit = cat[cat.name == name]
    if hit.empty:
        raise DataError(f"{folder}: no dataset {name!r}; there are: {', '.join(cat.name)}")
    path = Path(hit.path.iloc[0])  # as the workflow named it, from its working folder
    _, doc = describe(path)
    return read(folder.joinpath(*path.parts[-len(Path(doc.pattern).parts):]))  # its place in this run folder


def outputs_table() -> str:
    """docs/outputs.md's table of datasets (Markdown), from :data:`DATASETS`."""
    lines = ["| name | file under `results/<run>/` | one row per | what it holds |", "|---|---|---|---|"]
    lines += [f"| `{d.name}` | `{d.pattern}` | {d.row} | {d.description} |" for d in DATASETS]
    return "\n".join(lines)


_BEGIN, _END = "<!-- datasets: generated by python -m capmap.io.catalogue --write -->", "<!-- end of datasets -->"


def _write(doc: Path) -> None:
    text = doc.read_text()
    head, rest = text.split(_BEGIN, 1)
    tail = rest.split(_END, 1)[1]
    doc.write_text(f"{head}{_BEGIN}\n{outputs_table()}\n{_END}{tail}")


if __name__ == "__main__":  # python -m capmap.io.catalogue --write docs/outputs.md
    if sys.argv[1:2] == ["--write"]:
        _write(Path(sys.argv[2]))
    else:
        print(outputs_table())
