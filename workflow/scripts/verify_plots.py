from capmap.io.logs import call
from capmap.stages.verify_figures import stage_verify_plots

call(stage_verify_plots, voxels=snakemake.input.voxels, configurations=snakemake.input.configurations,
     timeseries=snakemake.input.timeseries, out=dict(snakemake.output.items()), slice_json=snakemake.params.slice,
     colour=snakemake.params.colour, log=snakemake.log[0])
