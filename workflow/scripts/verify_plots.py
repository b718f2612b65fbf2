from capmap.io.logs import call

call("capmap.stages.verify_figures:stage_verify_plots",
     voxels=snakemake.input.voxels, configurations=snakemake.input.configurations,
     timeseries=snakemake.input.timeseries, out=dict(snakemake.output.items()), slice_json=snakemake.params.slice,
     colour=snakemake.params.colour, log=snakemake.log[0])
