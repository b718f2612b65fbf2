from capmap.pipeline import run, stage_summary

run(stage_summary, voxels=snakemake.input.voxels, points=snakemake.input.points, out_csv=snakemake.output.csv,
    out_md=snakemake.output.md, out_png=snakemake.output.png, slice_json=snakemake.params.slice, log=snakemake.log[0])
