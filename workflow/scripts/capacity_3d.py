from capmap.io.logs import call

call("capmap.stages.capacity_figures:stage_capacity_3d",
     voxels=snakemake.input.voxels, configurations=snakemake.input.configurations,
     waypoints=list(snakemake.input.waypoints), task_waypoints=dict(zip(snakemake.params.tasks, snakemake.input.tasks)),
     out_html=snakemake.output[0], slice_json=snakemake.params.slice, verified=list(snakemake.input.verified),
     log=snakemake.log[0])
