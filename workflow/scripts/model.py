from capmap.pipeline import run, stage_model

run(stage_model, robot_yaml=snakemake.input.robot, out=snakemake.output[0], slice_json=snakemake.params.slice,
    log=snakemake.log[0])
