rule model:
    """Load and validate the robot; write its joint/link table."""
    input:
        robot=config["robot"],
    output:
        "results/model/joints.parquet",
    params:
        slice=slice_json("model"),
    log:
        "results/logs/model.log",
    script:
        "../scripts/model.py"
