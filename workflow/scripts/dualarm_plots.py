from capmap.io.logs import call
from capmap.stages.dualarm_figures import stage_dualarm_plots

call(stage_dualarm_plots, trajectory=snakemake.input.trajectory, fine=snakemake.input.fine, outer=snakemake.input.outer,
     torques_file=snakemake.input.torques, out=dict(snakemake.output.items()), log=snakemake.log[0])
