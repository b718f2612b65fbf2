from capmap.pipeline import run, stage_catalogue

run(stage_catalogue, paths=list(snakemake.input), out=snakemake.output[0], log=snakemake.log[0])
