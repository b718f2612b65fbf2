from capmap.io.logs import call

call("capmap.stages.verify:stage_verify", waypoints=snakemake.input.waypoints, out_timeseries=snakemake.output.timeseries,
     out_segments=snakemake.output.segments, out_csv=snakemake.output.csv, out_md=snakemake.output.md,
     slice_json=snakemake.params.slice, log=snakemake.log[0])
