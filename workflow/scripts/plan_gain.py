from capmap.io.logs import call

call("capmap.stages.gain:stage_plan_gain",
     voxels=snakemake.input.voxels, out_tasks=snakemake.output.tasks, out_csv=snakemake.output.csv,
     out_md=snakemake.output.md, slice_json=snakemake.params.slice, log=snakemake.log[0])
