# Validation and config slices: run once, before any job (snakemake-workflows' common.smk).
import sys

from capmap.config import (canonical, check_run_config, dualarm_slices, follow_slices, payload_label, reconfig_slices,
                           stage_slices)
from capmap.errors import CapmapError

# validate once, before any job: schema, robot file, locked joint, limits, task poses, follow cases
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
