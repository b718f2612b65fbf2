from capmap.io.logs import call

call("capmap.stages.advice:stage_advice", tasks_path=snakemake.input.tasks, healthy_path=snakemake.input.healthy,
     out=dict(snakemake.output.items()), slice_json=snakemake.params.slice, joint=int(snakemake.wildcards.joint),
     log=snakemake.log[0])
