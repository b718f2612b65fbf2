from capmap.io.logs import call

call("capmap.stages.capacity:stage_points",
     shards=list(snakemake.input.shards), out=snakemake.output[0], slice_json=snakemake.params.slice,
     log=snakemake.log[0])
