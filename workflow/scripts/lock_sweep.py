from capmap.io.logs import call
from capmap.stages.lock_sweep import stage_lock_sweep

call(stage_lock_sweep, out=snakemake.output[0], slice_json=snakemake.params.slice, joint=int(snakemake.wildcards.joint),
     stands_at_deg=float(snakemake.params.stands_at), log=snakemake.log[0])
