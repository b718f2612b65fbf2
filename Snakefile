# capmap: capacity maps of a manipulator with a locked joint.
#   snakemake --cores 2 all                       (default config/config.yaml)
#   snakemake --cores 2 all --configfile my.yaml  (a complete config: replaces the default)
import sys

from snakemake.utils import min_version

min_version("8.0")


# the default config only when no --configfile is given: a config file is complete on its own
# (a deep merge over the default would leak keys such as directions.step_deg into other kinds)
if not workflow.overwrite_configfiles:

    configfile: "config/config.yaml"


from capmap.config import canonical, check_run_config, follow_slices, payload_label, stage_slices
from capmap.errors import CapmapError

# validate once, before any job: schema, robot file, locked joint, limits
try:
    RUN = check_run_config(config)
except CapmapError as exc:
    sys.exit(f"capmap: {exc}")
SLICES = stage_slices(config)
SHARDS = RUN.shards
PAYLOADS = [payload_label(m) for m in RUN.task.payload_kg]  # wildcard values, e.g. "1500"
FOLLOW_SLICES = follow_slices(config)
FOLLOW_CASES = list(FOLLOW_SLICES)  # "space", "ground": those configured under follow
PAYLOAD_RE = "|".join(p.replace(".", r"\.") for p in PAYLOADS)


def slice_json(stage, payload=None):
    """Canonical JSON of the config slice a stage depends on (rule params: exact reruns).
    plan/verify jobs handle one payload each and depend on that payload only."""
    if payload is None:
        return canonical(SLICES[stage]["upstream"])
    return canonical(stage_slices(config, float(payload))[stage]["upstream"])


include: "workflow/rules/model.smk"
include: "workflow/rules/sample.smk"
include: "workflow/rules/capacity.smk"
include: "workflow/rules/voxels.smk"
include: "workflow/rules/plan.smk"
include: "workflow/rules/verify.smk"
include: "workflow/rules/follow.smk"
include: "workflow/rules/catalogue.smk"


rule all:
    input:
        "results/voxels/voxels.parquet",
        "results/summary/capacity_summary.csv",
        expand("results/verify/payload_{payload}kg/{name}.png", payload=PAYLOADS,
               name=["workspace", "torques", "base_force", "base_moment"]),
        "results/verify/summary.csv",
        expand("results/follow/{case}/{name}.png", case=FOLLOW_CASES, name=["progress", "torques"]),
        ["results/follow/summary.csv"] if FOLLOW_CASES else [],
        "results/catalogue.parquet",
    default_target: True
