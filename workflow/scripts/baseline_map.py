from capmap.io.logs import call
from capmap.stages.baseline import stage_baseline_map

call(stage_baseline_map, shards=list(snakemake.input.shards), voxels=snakemake.input.voxels,
     configurations=snakemake.input.configurations, out=snakemake.output.voxels,
     out_convergence=snakemake.output.convergence, out_csv=snakemake.output.csv, out_md=snakemake.output.md,
     slice_json=snakemake.params.slice, log=snakemake.log[0])
