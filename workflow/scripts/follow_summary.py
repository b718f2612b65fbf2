from capmap.pipeline import run, stage_follow_summary

run(stage_follow_summary, tables=list(snakemake.input), out_csv=snakemake.output.csv, out_md=snakemake.output.md,
    log=snakemake.log[0])
