from capmap.io.logs import call

call("capmap.stages.atlas:stage_atlas_map", out_voxels=snakemake.output.voxels, out_summary=snakemake.output.summary,
     slice_json=snakemake.params.slice, joint=int(snakemake.wildcards.joint),
     angle_deg=float(snakemake.wildcards.angle), log=snakemake.log[0])
