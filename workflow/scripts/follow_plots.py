from capmap.io.logs import call
from capmap.stages.following_figures import stage_follow_plots

call(stage_follow_plots, timeseries=snakemake.input.timeseries, toppra=snakemake.input.toppra, out=dict(snakemake.output.items()),
     slice_json=snakemake.params.slice, log=snakemake.log[0])
