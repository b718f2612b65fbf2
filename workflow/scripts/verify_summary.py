from capmap.pipeline import run, stage_concat_summary

run(stage_concat_summary, tables=list(snakemake.input), out_csv=snakemake.output.csv, out_md=snakemake.output.md,
    what="verify", log=snakemake.log[0])
