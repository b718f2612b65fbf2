from capmap.io.logs import call
from capmap.stages.verify import stage_plan

call(stage_plan, voxels=snakemake.input.voxels, out=snakemake.output[0], slice_json=snakemake.params.slice,
     log=snakemake.log[0])
