from capmap.io.logs import call

call("capmap.stages.dualarm_solve:stage_dualarm_optimise",
     environment=snakemake.input.environment, unknown=snakemake.input.unknown,
     capsules=snakemake.input.capsules,
     out=dict(snakemake.output.items()), slice_json=snakemake.params.slice, log=snakemake.log[0])
