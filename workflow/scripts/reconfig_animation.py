from capmap.io.logs import call
from capmap.stages.reconfig_figures import stage_reconfig_animation

call(stage_reconfig_animation, tables=list(snakemake.input.tables), out_html=snakemake.output[0],
     slice_json=snakemake.params.slice, log=snakemake.log[0])
