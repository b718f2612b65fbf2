from capmap.io.logs import call

call("capmap.stages.atlas:stage_atlas", summaries=list(snakemake.input.summaries), voxels=list(snakemake.input.voxels),
     out=dict(snakemake.output.items()), slice_json=snakemake.params.slice, log=snakemake.log[0])
