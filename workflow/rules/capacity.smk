rule capacity:
    """Shard k of n: every IK branch at the task orientation x every direction, per point."""
    input:
        points="results/sample/points.parquet",
    output:
        "results/capacity/shard_{k}_of_{n}.parquet",
    params:
        slice=slice_json("capacity"),
    log:
        "results/logs/capacity/shard_{k}_of_{n}.log",
    wildcard_constraints:
        k=r"\d+",
        n=r"\d+",
    script:
        "../scripts/capacity.py"
