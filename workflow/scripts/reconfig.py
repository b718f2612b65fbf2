from capmap.io.logs import call

call("capmap.stages.reconfig:stage_reconfig",
     method=snakemake.wildcards.method, out=snakemake.output.table, out_timing=snakemake.output.timing,
     slice_json=snakemake.params.slice, log=snakemake.log[0])
