DATASETS = [
    out("model/joints.parquet"),
    out("capacity/points.parquet"),
    out("voxels/voxels.parquet"),
    out("voxels/configurations.parquet"),
    *expand(out("plan/payload_{payload}kg/waypoints.parquet"), payload=PAYLOADS),
    *expand(out("tasks/{task}/{name}.parquet"), task=TASKS, name=["waypoints", "timeseries", "segments"]),
    *expand(out("verify/payload_{payload}kg/{name}.parquet"), payload=PAYLOADS, name=["timeseries", "segments"]),
    *expand(out("follow/{case}/{name}.parquet"), case=FOLLOW_CASES, name=["timeseries", "toppra"]),
    *expand(out("reconfig/{method}.parquet"), method=RECONFIG_METHODS),
    *(
        [
            out(f"dualarm/{name}.parquet")
            for name in ("cloud", "environment", "unknown", "robot_capsules", "trajectory", "fine", "outer", "torques")
        ]
        if DUALARM
        else []
    ),
]

# outputs an earlier config of this run left behind (a payload, task, case or family since removed):
# named here, kept on disk, never in the catalogue or the report
STALE = stale_outputs(
    OUT,
    {
        "plan/payload_*kg": [f"plan/payload_{p}kg" for p in PAYLOADS],
        "verify/payload_*kg": [f"verify/payload_{p}kg" for p in PAYLOADS],
        "tasks/*": [f"tasks/{t}" for t in TASKS],
        "follow/*": [f"follow/{c}" for c in (*FOLLOW_CASES, "summary.csv", "summary.md")] if FOLLOW_CASES else [],
        "capacity/shard_*_of_*.parquet": [f"capacity/shard_{k}_of_{SHARDS}.parquet" for k in range(SHARDS)],
        "voxels/refined_*_of_*.parquet": (
            [f"voxels/refined_{k}_of_{SHARDS}.parquet" for k in range(SHARDS)] if REFINE else []
        ),
        "voxels/configurations_*_of_*.parquet": (
            [f"voxels/configurations_{k}_of_{SHARDS}.parquet" for k in range(SHARDS)] if REFINE else []
        ),
        "reconfig": ["reconfig"] if RECONFIG_METHODS else [],
        "reconfig/*.parquet": [f"reconfig/{m}.parquet" for m in RECONFIG_METHODS],
        "dualarm": ["dualarm"] if DUALARM else [],
        "atlas": ["atlas"] if ATLAS_CASES else [],
        "atlas/joint*_angle*": [d[len(OUT) + 1 :] for d in ATLAS_DIRS],
        "baseline/healthy_*_of_*.parquet": [f"baseline/healthy_{k}_of_{SHARDS}.parquet" for k in range(SHARDS)],
    },
)
if STALE:
    print(
        f"capmap: note: {len(STALE)} output(s) under {OUT}/ are not of this config (kept, not in its catalogue "
        f"or report; delete them when no longer wanted): {', '.join(STALE)}",
        file=sys.stderr,
    )


rule catalogue:
    """List every dataset: name, path, stage, rows, columns with units, sha256, config hash."""
    input:
        DATASETS,
    output:
        out("catalogue.parquet"),
    log:
        out("logs/catalogue.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("catalogue"),
    script:
        "../scripts/catalogue.py"


# the tables of the report: (name, table of this run, report category, caption file in workflow/report/); each
# as an HTML page headed by its caption
TABLES = [
    ("catalogue", "catalogue.parquet", "Catalogue", "catalogue"),
    ("capacity_summary", "summary/capacity_summary.csv", "Capacity map", "summary"),
    ("verify_summary", "verify/summary.csv", "Verification", "verify_summary"),
    *([("follow_summary", "follow/summary.csv", "Following", "follow_summary")] if FOLLOW_CASES else []),
    *(
        [("reconfig_summary", "reconfig/summary.csv", "Reconfiguration", "reconfig_summary")]
        if RECONFIG_METHODS
        else []
    ),
    *(
        [
            ("dualarm_summary", "dualarm/summary.csv", "Dual-arm assembly", "dualarm_summary"),
            ("csqp_check", "dualarm/csqp_check.csv", "Dual-arm assembly", "dualarm_check"),
        ]
        if DUALARM
        else []
    ),
]
TABLE_PAGES = {name: out(f"report/{name}.html") for name, *_ in TABLES}
CAPTIONS = {
    name: (Path(workflow.basedir) / "workflow" / "report" / f"{rst}.rst").read_text() for name, *_, rst in TABLES
}


rule report_tables:
    """The catalogue and the summaries as HTML tables with their captions (the report's tables)."""
    input:
        **{name: out(path) for name, path, *_ in TABLES},
    output:
        **{
            name: report(TABLE_PAGES[name], category=cat, caption=f"../report/{rst}.rst")
            for name, _, cat, rst in TABLES
        },
    log:
        out("logs/report_tables.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=canonical({"stale": STALE, "captions": CAPTIONS, **json.loads(code_params("report_tables"))}),
    script:
        "../scripts/report_tables.py"
