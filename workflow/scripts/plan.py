from capmap.io.logs import call

call("capmap.stages.verify:stage_plan", voxels=snakemake.input.voxels, out=snakemake.output[0], slice_json=snakemake.params.slice,
     log=snakemake.log[0])
