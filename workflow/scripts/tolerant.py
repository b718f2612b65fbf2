from capmap.io.logs import call

call("capmap.stages.tolerant:stage_tolerant", sweep_paths=list(snakemake.input.sweeps), out=dict(snakemake.output.items()),
     slice_json=snakemake.params.slice, log=snakemake.log[0])
