from capmap.io.logs import call

call("capmap.stages.following:stage_follow", case=snakemake.wildcards.case, waypoints=snakemake.input.get("waypoints"),
     out_timeseries=snakemake.output.timeseries, out_toppra=snakemake.output.toppra, out_csv=snakemake.output.csv,
     out_md=snakemake.output.md, slice_json=snakemake.params.slice, log=snakemake.log[0])
