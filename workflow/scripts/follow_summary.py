from capmap.pipeline import run, stage_concat_summary

run(stage_concat_summary, tables=list(snakemake.input), out_csv=snakemake.output.csv, out_md=snakemake.output.md,
    what="follow", log=snakemake.log[0])
