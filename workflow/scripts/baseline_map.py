from capmap.io.logs import call

call("capmap.stages.baseline:stage_baseline_map", shards=list(snakemake.input.shards), voxels=snakemake.input.voxels,
     configurations=snakemake.input.configurations,
     out=dict(snakemake.output.items()), slice_json=snakemake.params.slice, workers=snakemake.threads,
     log=snakemake.log[0])
