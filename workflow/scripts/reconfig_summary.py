from capmap.io.logs import call

call("capmap.stages.reconfig:stage_reconfig_summary", tables=list(snakemake.input.tables), timings=list(snakemake.input.timings),
     out_csv=snakemake.output.csv, out_md=snakemake.output.md, log=snakemake.log[0])
