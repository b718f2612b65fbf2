from capmap.io.logs import call

call("capmap.stages.reconfig_figures:stage_reconfig_animation", tables=list(snakemake.input.tables), out_html=snakemake.output[0],
     slice_json=snakemake.params.slice, log=snakemake.log[0])
