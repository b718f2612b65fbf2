from capmap.io.logs import call
from capmap.stages.tolerant import stage_tolerant

call(stage_tolerant, sweep_paths=list(snakemake.input.sweeps), out=dict(snakemake.output.items()),
     slice_json=snakemake.params.slice, log=snakemake.log[0])
