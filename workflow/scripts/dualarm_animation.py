from capmap.io.logs import call

call("capmap.stages.dualarm_figures:stage_dualarm_animation",
     trajectory=snakemake.input.trajectory, environment=snakemake.input.environment,
     capsules=snakemake.input.capsules, out_html=snakemake.output[0], slice_json=snakemake.params.slice,
     log=snakemake.log[0])
