from capmap.io.logs import call

call("capmap.stages.lock_sweep:stage_lock_sweep",
     out=snakemake.output[0], slice_json=snakemake.params.slice, joint=int(snakemake.wildcards.joint),
     stands_at_deg=float(snakemake.params.stands_at), log=snakemake.log[0])
