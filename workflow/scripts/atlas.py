from capmap.io.logs import call
from capmap.stages.atlas import stage_atlas

call(stage_atlas, summaries=list(snakemake.input.summaries), voxels=list(snakemake.input.voxels),
     out_atlas=snakemake.output.atlas, out_curves=snakemake.output.curves, out_heatmap=snakemake.output.heatmap,
     out_curves_png=snakemake.output.curves_png, slice_json=snakemake.params.slice, log=snakemake.log[0])
