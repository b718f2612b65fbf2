DATASETS = [
    "results/model/joints.parquet",
    "results/sample/points.parquet",
    *expand("results/capacity/shard_{k}_of_{n}.parquet", k=range(SHARDS), n=SHARDS),
    "results/voxels/sampled.parquet",
    *(expand("results/voxels/refined_{k}_of_{n}.parquet", k=range(SHARDS), n=SHARDS) if REFINE else []),
    "results/voxels/voxels.parquet",
    "results/voxels/points.parquet",
    *expand("results/plan/payload_{payload}kg/waypoints.parquet", payload=PAYLOADS),
    "results/plan/gain_tasks.parquet",
    *expand("results/tasks/{task}/{name}.parquet", task=TASKS, name=["waypoints", "timeseries", "segments"]),
    *expand("results/verify/payload_{payload}kg/{name}.parquet", payload=PAYLOADS, name=["timeseries", "segments"]),
    *expand("results/follow/{case}/{name}.parquet", case=FOLLOW_CASES, name=["timeseries", "toppra"]),
    *expand("results/reconfig/{method}.parquet", method=RECONFIG_METHODS),
    *([f"results/dualarm/{name}.parquet" for name in ("cloud", "environment", "robot_capsules", "trajectory", "fine",
                                                       "outer")] if DUALARM else []),
]


rule catalogue:
    """List every dataset: name, path, stage, rows, columns with units, sha256, config hash."""
    input:
        DATASETS,
    output:
        report("results/catalogue.parquet", category="Catalogue"),
    params:
        code=with_code("{}", "catalogue"),
    log:
        "results/logs/catalogue.log",
    script:
        "../scripts/catalogue.py"
