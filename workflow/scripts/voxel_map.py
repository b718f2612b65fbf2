from capmap.io.logs import call

call("capmap.stages.refine:stage_voxel_map", sampled=snakemake.input.sampled, refined=list(snakemake.input.refined),
     configurations=list(snakemake.input.configurations), out=snakemake.output.voxels,
     out_configurations=snakemake.output.configurations, slice_json=snakemake.params.slice, log=snakemake.log[0])
