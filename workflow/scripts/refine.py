from capmap.io.logs import call

call("capmap.stages.refine:stage_refine", voxels=snakemake.input.voxels, out=snakemake.output.voxels,
     out_configurations=snakemake.output.configurations, slice_json=snakemake.params.slice,
     shard=int(snakemake.wildcards.k), shards=int(snakemake.wildcards.n), log=snakemake.log[0])
