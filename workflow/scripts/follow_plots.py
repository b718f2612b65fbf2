from capmap.io.logs import call

call("capmap.stages.following_figures:stage_follow_plots",
     timeseries=snakemake.input.timeseries, toppra=snakemake.input.toppra, out=dict(snakemake.output.items()),
     slice_json=snakemake.params.slice, log=snakemake.log[0])
