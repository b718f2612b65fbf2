from capmap.pipeline import run, stage_voxels

run(stage_voxels, shards=list(snakemake.input.shards), out_voxels=snakemake.output.voxels,
    out_points=snakemake.output.points, slice_json=snakemake.params.slice, log=snakemake.log[0])
