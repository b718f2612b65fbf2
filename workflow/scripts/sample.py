from capmap.pipeline import run, stage_sample

run(stage_sample, out=snakemake.output[0], slice_json=snakemake.params.slice, log=snakemake.log[0])
