from capmap.io.logs import call

call("capmap.stages.capacity_figures:stage_baseline_figure",
     voxels=snakemake.input.voxels, convergence=snakemake.input.convergence,
     out_png=snakemake.output[0], slice_json=snakemake.params.slice, log=snakemake.log[0])
