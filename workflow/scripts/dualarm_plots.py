from capmap.io.logs import call
from capmap.stages.dualarm_figures import stage_dualarm_plots

call(stage_dualarm_plots, trajectory=snakemake.input.trajectory, fine=snakemake.input.fine, outer=snakemake.input.outer,
     torques_file=snakemake.input.torques, out_errors=snakemake.output.errors, out_distances=snakemake.output.distances,
     out_joints=snakemake.output.joints, out_velocities=snakemake.output.velocities, out_torques=snakemake.output.torques,
     out_convergence=snakemake.output.convergence, log=snakemake.log[0])
