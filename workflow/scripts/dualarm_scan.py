from capmap.io.logs import call

call("capmap.stages.dualarm:stage_dualarm_scan", out=snakemake.output[0], slice_json=snakemake.params.slice, log=snakemake.log[0])
