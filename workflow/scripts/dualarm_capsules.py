from capmap.io.logs import call
from capmap.stages.dualarm import stage_dualarm_capsules

call(stage_dualarm_capsules, out=snakemake.output[0], slice_json=snakemake.params.slice, log=snakemake.log[0])
