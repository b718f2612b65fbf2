from capmap.io.logs import call
from capmap.stages.capacity_figures import stage_baseline_figure

call(stage_baseline_figure, voxels=snakemake.input.voxels, convergence=snakemake.input.convergence,
     out_png=snakemake.output[0], slice_json=snakemake.params.slice, log=snakemake.log[0])
