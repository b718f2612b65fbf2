# The healthy arm and what the failure cost (not part of `all`: its cost is stated in the README):
#   snakemake --cores 2 baseline


rule baseline_shard:
    """Shard k of n of the healthy arm's voxels: the failed joint's angle swept, each voxel's minimum refined."""
    input:
        voxels=out("voxels/voxels.parquet"),
    output:
        out("baseline/healthy_{k}_of_{n}.parquet"),
    log:
        out("logs/baseline/shard_{k}_of_{n}.log"),
    wildcard_constraints:
        k=r"\d+",
        n=r"\d+",
    conda:
        "../envs/capmap.yaml"
    params:
        slice=params("baseline_shard", "baseline_shard"),
    script:
        "../scripts/baseline_shard.py"


rule baseline_map:
    """The healthy map beside the failed one: the loss per voxel, the angle step's convergence, the summary."""
    input:
        shards=expand(out("baseline/healthy_{k}_of_{n}.parquet"), k=range(SHARDS), n=SHARDS),
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
    output:
        voxels=out("baseline/voxels.parquet"),
        convergence=out("baseline/convergence.parquet"),
        csv=out("baseline/summary.csv"),
        md=out("baseline/summary.md"),
    log:
        out("logs/baseline/map.log"),
    conda:
        "../envs/capmap.yaml"
    threads: 2  # the angle step's check (a 1 deg sweep at 200 points) on two processes
    params:
        slice=params("baseline", "baseline_map"),
    script:
        "../scripts/baseline_map.py"


rule baseline_figure:
    """What the failure cost: capacity-volume curves, the healthy map and the loss, the angle step's check."""
    input:
        voxels=out("baseline/voxels.parquet"),
        convergence=out("baseline/convergence.parquet"),
    output:
        report(out("baseline/loss.png"), category="Healthy-arm baseline", caption="../report/baseline.rst"),
    log:
        out("logs/baseline/figure.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        slice=params("view", "baseline_figure"),
    script:
        "../scripts/baseline_figure.py"


rule baseline_catalogue:
    """Catalogue of the baseline datasets."""
    input:
        expand(out("baseline/healthy_{k}_of_{n}.parquet"), k=range(SHARDS), n=SHARDS),
        out("baseline/voxels.parquet"),
        out("baseline/convergence.parquet"),
    output:
        out("baseline/catalogue.parquet"),
    log:
        out("logs/baseline/catalogue.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("catalogue"),
    script:
        "../scripts/catalogue.py"


rule baseline:
    """Target: the healthy arm's map, the loss per voxel, its figure and summary."""
    input:
        out("baseline/voxels.parquet"),
        out("baseline/loss.png"),
        out("baseline/summary.csv"),
        out("baseline/catalogue.parquet"),
