from capmap.io.logs import call

call("capmap.stages.capacity:stage_model",
     robot_yaml=snakemake.input.robot, out=snakemake.output[0], slice_json=snakemake.params.slice,
     log=snakemake.log[0])
