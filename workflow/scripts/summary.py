from capmap.io.logs import call

call("capmap.stages.capacity_figures:stage_summary", voxels=snakemake.input.voxels, configurations=snakemake.input.configurations,
     points=snakemake.input.points, waypoints=list(snakemake.input.waypoints), out=dict(snakemake.output.items()),
     slice_json=snakemake.params.slice, verified=list(snakemake.input.verified), log=snakemake.log[0])
