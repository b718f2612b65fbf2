from capmap.io.logs import call
from capmap.stages.report import stage_concat_summary

call(stage_concat_summary, tables=list(snakemake.input), out_csv=snakemake.output.csv, out_md=snakemake.output.md,
     what="follow", log=snakemake.log[0])
