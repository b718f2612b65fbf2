from capmap.io.logs import call

call("capmap.stages.capacity:stage_voxels", points=snakemake.input.points, out_voxels=snakemake.output.voxels,
     slice_json=snakemake.params.slice, log=snakemake.log[0])
