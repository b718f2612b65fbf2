from capmap.io.logs import call
from capmap.stages.report import stage_catalogue

call(stage_catalogue, paths=list(snakemake.input), out=snakemake.output[0], log=snakemake.log[0])
