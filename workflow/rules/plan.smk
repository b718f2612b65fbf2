rule plan:
    """Improved A* through the voxels that carry the task payload (one job per payload)."""
    input:
        voxels="results/voxels/voxels.parquet",
    output:
        "results/plan/payload_{payload}kg/waypoints.parquet",
    params:
        slice=lambda w: slice_json("plan", w.payload),
    log:
        "results/logs/plan/payload_{payload}kg.log",
    wildcard_constraints:
        payload=PAYLOAD_RE,
    script:
        "../scripts/plan.py"
