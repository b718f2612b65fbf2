from capmap.io.logs import call
from capmap.stages.dualarm_solve import stage_dualarm_optimise

call(stage_dualarm_optimise, environment=snakemake.input.environment, unknown=snakemake.input.unknown,
     capsules=snakemake.input.capsules,
     out_trajectory=snakemake.output.trajectory, out_fine=snakemake.output.fine, out_outer=snakemake.output.outer,
     out_torques=snakemake.output.torques,
     out_csv=snakemake.output.csv, out_md=snakemake.output.md, slice_json=snakemake.params.slice, log=snakemake.log[0])
