from capmap.io.logs import call

call("capmap.stages.reconfig_figures:stage_reconfig_plots",
     tables=list(snakemake.input), out=dict(snakemake.output.items()), log=snakemake.log[0])
