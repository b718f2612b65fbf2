# Validation and config slices: run once, before any job (snakemake-workflows' common.smk).
import json
import shlex
import sys
from pathlib import Path

from capmap.capacity.sizing import check_parallel_memory
from capmap.checks import check_run_config
from capmap.config import canonical, main_task, payload_label, stage_slice
from capmap.config.run import DEFAULT_CONFIG
from capmap.config.slices import section_modules
from capmap.errors import CapmapError
from capmap.io.datasets import missing_catalogued, rebuild_hint_config
from capmap.plots.palette import path_colour
from capmap.io.fingerprint import script_fingerprint
from capmap.io.runs import check_writable, stale_outputs

CONFIG_ARGS = "".join(f" --configfile {shlex.quote(str(f))}" for f in workflow.overwrite_configfiles) + (
    " --config " + " ".join(shlex.quote(a) for a in workflow.config_settings.config_args)
    if workflow.config_settings.config_args
    else ""
)  # the run's config, repeated in printed commands
rebuild_hint_config(CONFIG_ARGS)  # the jobs' rebuild hints (capmap.io.datasets.read) name the config too

# validate once, before any job: schema, robot file, locked joint, limits, task poses, follow cases
try:
    RUN = check_run_config(config, ", ".join(CONFIG_FILES) or DEFAULT_CONFIG)
except CapmapError as exc:
    sys.exit(f"capmap: {exc}")
OUT = f"results/{RUN.name}"  # each run (config key `run`, else the config file's name) in its own folder


def _cores():
    try:
        return int(workflow.cores)
    except Exception:  # a dry run without --cores: one job at a time
        return 1


try:
    check_writable(OUT)
    if workflow.local_exec:  # the jobs share this machine (a cluster's jobs each have a node's memory)
        check_parallel_memory(RUN.estimate, _cores(), RUN.shards)
except CapmapError as exc:
    sys.exit(f"capmap: {exc}")


def out(path):
    """A path of this run's outputs: ``results/<run>/<path>`` (wildcards in braces kept)."""
    return f"{OUT}/{path}"


def mem_mb(kind):
    """A map job's memory request (MB): 1.5 x the pre-run estimate of its kind (capmap.capacity.sizing:
    capacity, voxels, refine, plan, verify, maps; a kind the run does not have, e.g. refine without
    voxels.refine: the largest), rounded up to 100 MB; what a cluster reserves per job."""
    est = RUN.estimate
    return int(-(-1.5 * est.jobs_mb.get(kind, est.peak_mb) // 100) * 100)


print(f"capmap: run {RUN.name!r}: outputs under {OUT}/", file=sys.stderr)
print(f"capmap: {RUN.failure.describe()}", file=sys.stderr)
print(f"capmap: {RUN.limits.describe()}", file=sys.stderr)
for (
    _t
) in RUN.tasks:  # a further task starts at the IK solution nearest its q_start_deg (the locked joint's value not used)
    print(
        f"capmap: task {_t.name}: start configuration [{', '.join(f'{v:.2f}' for v in _t.q_start_deg)}] deg",
        file=sys.stderr,
    )
# the report's scenario text (workflow/report/workflow.rst sees only the config): what the checks resolved
config["resolved"] = {
    "joint_torque_nm": RUN.limits.torque_text(),
    "torque_limit_source": RUN.limits.torque_limit_source,
}
print(f"capmap: estimate: {RUN.estimate.describe(RUN.voxel_edge_m)}", file=sys.stderr)
for _path in [
    p
    for c in (
        "catalogue.parquet",
        "atlas/catalogue.parquet",
        "baseline/catalogue.parquet",
        "plan/gain_catalogue.parquet",
    )
    for p in missing_catalogued(out(c))
]:
    # Snakemake would not rebuild it by itself (its consumers are up to date): say so, with the command
    print(
        f"capmap: warning: {_path} is in the catalogue but missing; rebuild it and what depends on it with: "
        f"snakemake --cores 2 all{CONFIG_ARGS} --forcerun {_path}",
        file=sys.stderr,
    )
SHARDS = RUN.shards
REFINE = RUN.refine is not None  # voxels.refine: false keeps the sampled minima
PLAN_JOBS = {payload_label(m): main_task(RUN.task, RUN.failure, m) for m in RUN.task.payload_kg}  # by payload label
PAYLOADS = list(PLAN_JOBS)  # wildcard values, e.g. "1500"
PAYLOAD_RE = "|".join(p.replace(".", r"\.") for p in PAYLOADS)
TASK_JOBS = {t.name: t for t in RUN.tasks}  # the further tasks of `tasks`, by name
TASKS = list(TASK_JOBS)
TASK_RE = "|".join(TASKS) or "(?!)"
# one plan / verify job per payload of the task and per further task; its folders (the rules' wildcards)
PLAN_DIRS = {
    **{f"plan/payload_{p}kg": j for p, j in PLAN_JOBS.items()},
    **{f"tasks/{t}": j for t, j in TASK_JOBS.items()},
}
VERIFY_DIRS = {
    **{f"verify/payload_{p}kg": f"plan/payload_{p}kg" for p in PAYLOADS},
    **{f"tasks/{t}": f"tasks/{t}" for t in TASKS},
}
PLAN_DIR_RE = "|".join(d.replace(".", r"\.") for d in PLAN_DIRS)
VERIFY_DIR_RE = "|".join(d.replace(".", r"\.") for d in VERIFY_DIRS)
FOLLOW_CASES = list(RUN.follow.cases) if RUN.follow else []  # "space", "ground": those configured under follow


def params(stage, script, job=None):
    """A rule's params: the canonical JSON of its stage's slice (capmap.config.slices: the config
    fields it reads, and the content hashes of the files they name) plus the fingerprint of the code
    it runs (the script's syntax tree and every capmap module it imports; capmap.io.fingerprint), so
    that a change of either reruns it and a comment does not. Recorded in the outputs' provenance."""
    sl = stage_slice(RUN, stage, job)
    return canonical({**sl, "code": script_fingerprint(_script(script), section_modules(sl))})


def code_params(script):
    """Params that hold only the code: for rules reading no config (tables, figures of upstream outputs)."""
    return canonical({"code": script_fingerprint(_script(script))})


def _script(name):
    return Path(workflow.basedir) / "workflow" / "scripts" / f"{name}.py"


def plan_dir_of(verify_dir):
    """The plan folder of a verify folder (verify/payload_<m>kg -> plan/payload_<m>kg; tasks/<name> itself)."""
    return VERIFY_DIRS[verify_dir]


def job_of(job_dir):
    """The plan/verify job of its plan or verify folder: a payload of the main task, or a further task."""
    return PLAN_DIRS[VERIFY_DIRS.get(job_dir, job_dir)]


def path_colour_of(verify_dir):
    """The colour of a verify folder's planned path: a main payload's by its place among the payloads, a further
    task's after them (capmap.plots.palette: the same on the summary map and the 3D page)."""
    job = job_of(verify_dir)
    return path_colour(RUN.task.payload_kg, job.payload_kg, TASKS.index(job.name) if job.name else None)


def follow_job():
    """The plan/verify job whose path the space case follows (its payload's)."""
    return PLAN_JOBS[payload_label(RUN.follow.space.payload_kg)]


def follow_inputs(wildcards):
    """space: the plan of its payload (the path it follows); ground: the robot file."""
    if wildcards.case == "space":
        return {"waypoints": out(f"plan/payload_{payload_label(RUN.follow.space.payload_kg)}kg/waypoints.parquet")}
    return {"robot": RUN.follow.ground.robot}


def dualarm_files(*keys):
    """Input files of the dual-arm section (the scene, the robot file, a user's cloud)."""
    da = RUN.dualarm
    if da is None:
        return []
    return [getattr(da, k) for k in keys] + ([da.cloud_file] if "scene" in keys and da.cloud_file else [])


# the lock-angle advice (rules/advice.smk)
ADVICE = RUN.advice is not None  # with an atlas section: the advice's maps are the atlas' settings
N_JOINTS = len(RUN.failure.q_start_deg)
ADVICE_JOINTS = list(RUN.advice.joints_of(RUN.failure.joint)) if ADVICE else []


def stands_at(wildcards):
    """The angle joint {joint} stands at: the failed one's lock angle, another's angle when it failed."""
    j = int(wildcards.joint)
    return RUN.failure.angle_deg if j == RUN.failure.joint else RUN.task.q_ini_deg[j - 1]


def advice_params(stage):
    """A rule's params; without an atlas section (no advice), one line and no job (asked for while the DAG is built)."""
    if not ADVICE:
        sys.exit(
            "capmap: advise: the config has no atlas section: the advice uses the atlas' maps (its sampling and edge)"
        )
    return params(stage, stage)
