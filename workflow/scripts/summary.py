from capmap.io.logs import call
from capmap.stages.capacity_figures import stage_summary

call(stage_summary, voxels=snakemake.input.voxels, configurations=snakemake.input.configurations,
     points=snakemake.input.points, waypoints=list(snakemake.input.waypoints), out=dict(snakemake.output.items()),
     slice_json=snakemake.params.slice, verified=list(snakemake.input.verified), log=snakemake.log[0])
