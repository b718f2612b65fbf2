# Validation and config slices: run once, before any job (snakemake-workflows' common.smk).
import json
import sys
from pathlib import Path

from capmap.config import (task_slices, atlas_slices, canonical, check_run_config, dualarm_slices, follow_slices, payload_label,
                           reconfig_slices, resolved_doc, stage_slices)
from capmap.config.capacity import refine_doc
from capmap.errors import CapmapError
from capmap.io.datasets import missing_catalogued
from capmap.io.fingerprint import script_fingerprint
from capmap.io.runs import stale_outputs

# validate once, before any job: schema, robot file, locked joint, limits, task poses, follow cases
try:
    RUN = check_run_config(config, ", ".join(map(str, workflow.overwrite_configfiles)) or "config/config.yaml")
except CapmapError as exc:
    sys.exit(f"capmap: {exc}")
OUT = f"results/{RUN.name}"  # each run (config key `run`, else the config file's name) in its own folder


def out(path):
    """A path of this run's outputs: ``results/<run>/<path>`` (wildcards in braces kept)."""
    return f"{OUT}/{path}"


print(f"capmap: run {RUN.name!r}: outputs under {OUT}/", file=sys.stderr)
print(f"capmap: {RUN.failure.describe()}", file=sys.stderr)
print(f"capmap: estimate: {RUN.estimate.describe(RUN.voxel_edge_m)}", file=sys.stderr)
for _path in missing_catalogued(out("catalogue.parquet")) + missing_catalogued(out("atlas/catalogue.parquet")):
    # Snakemake would not rebuild it by itself (its consumers are up to date): say so, with the command
    print(f"capmap: warning: {_path} is in the catalogue but missing; rebuild it and what depends on it with: "
          f"snakemake --cores 2 all --forcerun {_path}", file=sys.stderr)
DOC = resolved_doc(config, RUN.failure)  # lock angle, start and start configuration resolved
SLICES = stage_slices(DOC)
SHARDS = RUN.shards
REFINE = refine_doc(config["voxels"]) is not None  # voxels.refine: false keeps the sampled minima
PAYLOADS = [payload_label(m) for m in RUN.task.payload_kg]  # wildcard values, e.g. "1500"
FOLLOW_SLICES = follow_slices(DOC)
FOLLOW_CASES = list(FOLLOW_SLICES)  # "space", "ground": those configured under follow
PAYLOAD_RE = "|".join(p.replace(".", r"\.") for p in PAYLOADS)
TASK_SLICES = task_slices(DOC)  # the further tasks of `tasks`, by name
TASKS = list(TASK_SLICES)
TASK_RE = "|".join(TASKS) or "(?!)"


def slice_json(stage, payload=None):
    """Canonical JSON of the config slice a stage depends on (a rule's params, for exact reruns).
    plan/verify jobs handle one payload each and depend on that payload only."""
    if payload is None:
        return canonical(SLICES[stage]["upstream"])
    return canonical(stage_slices(DOC, float(payload))[stage]["upstream"])


def with_code(slice_json_text, script):
    """A rule's params: its config slice plus the fingerprint of the code it runs (the script's
    syntax tree and every capmap module it imports; see capmap.io.fingerprint), so that a change
    of the numerics reruns it and a comment does not. Recorded in the outputs' provenance."""
    path = Path(workflow.basedir) / "workflow" / "scripts" / f"{script}.py"
    return canonical({**json.loads(slice_json_text), "code": script_fingerprint(path)})


def view_json(stage):
    """A figure's params: the stage's slice plus what the map's figures mark (start, goal, payloads)."""
    task = DOC["task"]
    view = {"start_m": task["start_m"], "goal_m": task["goal_m"], "payloads_kg": list(RUN.task.payload_kg)}
    return canonical({**json.loads(slice_json(stage)), "view": view})


def follow_inputs(wildcards):
    """space: the plan of its payload (the path it follows); ground: the robot file."""
    if wildcards.case == "space":
        m = payload_label(config["follow"]["space"]["payload_kg"])
        return {"waypoints": out(f"plan/payload_{m}kg/waypoints.parquet")}
    return {"robot": config["follow"]["ground"]["robot"]}


def dualarm_json(rule):
    return canonical(DUALARM_SLICES[rule])


def dualarm_files(*keys):
    """Input files of the dual-arm section (the scene, the robot file, a user's cloud)."""
    da = config.get("dualarm", {})
    return [da[k] for k in keys if k in da] + ([da["cloud"]["file"]] if "scene" in keys and "file" in da.get("cloud", {}) else [])
