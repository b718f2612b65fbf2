from capmap.io.logs import call

call("capmap.stages.dualarm_solve:stage_dualarm_check",
     environment=snakemake.input.environment, capsules=snakemake.input.capsules,
     out_csv=snakemake.output.csv, out_md=snakemake.output.md, slice_json=snakemake.params.slice, log=snakemake.log[0])
