from capmap.io.logs import call
from capmap.stages.reconfig import stage_reconfig

call(stage_reconfig, method=snakemake.wildcards.method, out=snakemake.output.table, out_timing=snakemake.output.timing,
     slice_json=snakemake.params.slice, log=snakemake.log[0])
