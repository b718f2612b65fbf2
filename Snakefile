# capmap: capacity maps of a manipulator with a locked joint, torque-limited following, boom reconfiguration,
# dual-arm assembly in a confined space.
#   snakemake --cores 2 all                       (default config/config.yaml)
#   snakemake --cores 2 all --configfile my.yaml  (a complete config: replaces the default)
from snakemake.utils import min_version

min_version("8.0")


# The run's config, read once by capmap's own loader (bounded, no YTE templates, no duplicate keys):
# the config file named by `--config configfile=my.yaml` (what `capmap run my.yaml` passes: Snakemake
# never opens it), else the --configfile(s), else config/config.yaml, then the other --config overrides.
# A config file is complete on its own (a deep merge over the default would leak keys such as
# directions.step_deg into other kinds). Snakemake parses a --configfile itself first (and evaluates
# YTE in it): for a config one did not write, use `capmap run` (README).
import sys

from capmap.config.run import config_files, run_document
from capmap.errors import CapmapError

try:
    CONFIG_FILES, _overrides = config_files(workflow.overwrite_configfiles, workflow.config_settings.config)
    _doc = run_document(CONFIG_FILES, _overrides)
except CapmapError as exc:
    sys.exit(f"capmap: {exc}")
config.clear()
config.update(_doc)


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/capacity.smk"
include: "workflow/rules/following.smk"
include: "workflow/rules/reconfig.smk"
include: "workflow/rules/dualarm.smk"
include: "workflow/rules/atlas.smk"
include: "workflow/rules/baseline.smk"
include: "workflow/rules/advice.smk"
include: "workflow/rules/catalogue.smk"


CAPACITY_MAP = [
    out("voxels/voxels.parquet"),
    out("summary/capacity_summary.csv"),
    out("summary/capacity_3d.html"),
    *expand(
        out("verify/payload_{payload}kg/{name}.png"),
        payload=PAYLOADS,
        name=["workspace", "torques", "base_force", "base_moment"],
    ),
    out("verify/summary.csv"),
    *expand(out("tasks/{task}/{name}.png"), task=TASKS, name=["workspace", "torques", "base_force", "base_moment"]),
]


rule capacity_map:
    # method family 1 alone: map, plans, verification and their figures
    input:
        CAPACITY_MAP,


rule all:
    default_target: True
    input:
        CAPACITY_MAP,
        expand(out("follow/{case}/{name}.png"), case=FOLLOW_CASES, name=["progress", "torques", "torque_split"]),
        [out("follow/summary.csv")] if FOLLOW_CASES else [],
        [
            out(f"reconfig/{name}")
            for name in ("summary.csv", "manipulability.png", "joint_rates.png", "passive_joint.png", "animation.html")
        ]
        if RECONFIG_METHODS
        else [],
        [
            out(f"dualarm/{name}")
            for name in (
                "summary.csv",
                "csqp_check.csv",
                "constraint_errors.png",
                "distances.png",
                "joints.png",
                "velocities.png",
                "torques.png",
                "convergence.png",
                "animation.html",
            )
        ]
        if DUALARM
        else [],
        out("catalogue.parquet"),
        list(TABLE_PAGES.values()),


onstart:
    # compile the numba kernels once, before the first job, so that parallel jobs load them instead of each
    # compiling them (capmap.kernels); the marker says in milliseconds when this code's are compiled already
    import os
    import subprocess
    import numpy as np
    from capmap.io import job_server
    from capmap.io.job_client import ENV
    from capmap.io.kernel_marker import is_warm, run_key

    _robot = str(Path(RUN.robot).resolve())
    _joint, _angle_deg, _dualarm = RUN.failure.joint, RUN.failure.angle_deg, RUN.dualarm is not None
    if not is_warm(run_key(_robot, _joint, np.deg2rad(_angle_deg), _dualarm, len(RUN.failure.q_start_deg))):
        subprocess.run(
            [
                sys.executable,
                "-m",
                "capmap.kernels",
                "--robot",
                _robot,
                "--joint",
                str(_joint),
                "--angle-deg",
                repr(_angle_deg),
            ]
            + (["--dualarm"] if _dualarm else []),
            check=False,
        )
    # warm jobs: a local run's jobs run in children of one process that has imported the stages and loaded
    # the kernels, about a second saved per job (capmap.io.job_server); a cluster's jobs run their own
    if workflow.local_exec and not os.environ.get(ENV):
        os.environ[ENV] = job_server.start(
            job_server.stage_modules(Path(workflow.basedir, "workflow", "scripts"), _dualarm),
            (
                "capmap.kernels:warm",
                dict(
                    robot_file=_robot,
                    joint=_joint,
                    angle_rad=float(np.deg2rad(_angle_deg)),
                    dualarm=_dualarm,
                    here=True,
                ),
            ),
        ).path


onsuccess:
    # the run's headline: per family the answer in a line or two, from the summary tables (capmap.stages.headline)
    from capmap.stages.headline import headline

    _lines = headline(OUT)
    if _lines:
        print("capmap: what this run found:\n" + "\n".join(f"  {line}" for line in _lines), file=sys.stderr)
