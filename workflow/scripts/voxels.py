from capmap.io.logs import call
from capmap.stages.capacity import stage_voxels

call(stage_voxels, shards=list(snakemake.input.shards), out_voxels=snakemake.output.voxels,
     out_points=snakemake.output.points, slice_json=snakemake.params.slice, log=snakemake.log[0])
