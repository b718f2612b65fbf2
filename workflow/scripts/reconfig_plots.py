from capmap.io.logs import call
from capmap.stages.reconfig_figures import stage_reconfig_plots

call(stage_reconfig_plots, tables=list(snakemake.input), out=dict(snakemake.output.items()), log=snakemake.log[0])
