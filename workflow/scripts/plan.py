from capmap.pipeline import run, stage_plan

run(stage_plan, voxels=snakemake.input.voxels, out=snakemake.output[0], slice_json=snakemake.params.slice,
    log=snakemake.log[0])
