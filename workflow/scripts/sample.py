from capmap.io.logs import call
from capmap.stages.capacity import stage_sample

call(stage_sample, out=snakemake.output[0], slice_json=snakemake.params.slice, log=snakemake.log[0])
