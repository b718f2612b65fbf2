from capmap.io.logs import call

call("capmap.stages.dualarm_figures:stage_dualarm_plots",
     trajectory=snakemake.input.trajectory, fine=snakemake.input.fine, outer=snakemake.input.outer,
     torques_file=snakemake.input.torques, out=dict(snakemake.output.items()), log=snakemake.log[0])
