rule sample:
    """Monte Carlo workspace of the locked arm (seeded)."""
    input:
        model="results/model/joints.parquet",
    output:
        "results/sample/points.parquet",
    params:
        slice=slice_json("sample"),
    log:
        "results/logs/sample.log",
    script:
        "../scripts/sample.py"
