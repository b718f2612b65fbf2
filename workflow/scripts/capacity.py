from capmap.io.logs import call

call("capmap.stages.capacity:stage_capacity",
     points=snakemake.input.points, out=snakemake.output[0], slice_json=snakemake.params.slice,
     shard=int(snakemake.wildcards.k), shards=int(snakemake.wildcards.n), log=snakemake.log[0])
