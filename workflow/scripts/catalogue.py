from capmap.io.logs import call

call("capmap.stages.report:stage_catalogue", paths=list(snakemake.input), out=snakemake.output[0], log=snakemake.log[0])
