rule voxels:
    """Gather the shards into the voxel grid (minimum capacity per voxel)."""
    input:
        shards=expand("results/capacity/shard_{k}_of_{n}.parquet", k=range(SHARDS), n=SHARDS),
    output:
        voxels="results/voxels/voxels.parquet",
        points="results/voxels/points.parquet",
    params:
        slice=slice_json("voxels"),
    log:
        "results/logs/voxels.log",
    script:
        "../scripts/voxels.py"


rule summary:
    """Capacity summary table and workspace figure (in the report)."""
    input:
        voxels="results/voxels/voxels.parquet",
        points="results/voxels/points.parquet",
    output:
        csv=report("results/summary/capacity_summary.csv", category="Capacity map", caption="../report/summary.rst"),
        md="results/summary/capacity_summary.md",
        png=report("results/summary/capacity_map.png", category="Capacity map", caption="../report/capacity_map.rst"),
    params:
        slice=slice_json("voxels"),
    log:
        "results/logs/summary.log",
    script:
        "../scripts/summary.py"
