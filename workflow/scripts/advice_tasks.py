from capmap.io.logs import call

call("capmap.stages.advice:stage_advice_tasks",
     sweep_path=snakemake.input.sweep, plans=list(snakemake.input.plans), out=dict(snakemake.output.items()),
     slice_json=snakemake.params.slice, joint=int(snakemake.wildcards.joint), log=snakemake.log[0])
