from capmap.io.logs import call
from capmap.stages.capacity import stage_model

call(stage_model, robot_yaml=snakemake.input.robot, out=snakemake.output[0], slice_json=snakemake.params.slice,
     log=snakemake.log[0])
