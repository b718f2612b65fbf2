from capmap.io.logs import call
from capmap.stages.reconfig_figures import stage_reconfig_plots

call(stage_reconfig_plots, tables=list(snakemake.input), out_manipulability=snakemake.output.manipulability,
     out_rates=snakemake.output.rates, out_passive=snakemake.output.passive, log=snakemake.log[0])
