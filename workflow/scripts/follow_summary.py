from capmap.io.logs import call

call("capmap.stages.report:stage_concat_summary",
     tables=list(snakemake.input), out_csv=snakemake.output.csv, out_md=snakemake.output.md,
     what="follow", log=snakemake.log[0])
