import json

from capmap.io.logs import call

call("capmap.stages.report:stage_report_tables", tables=dict(snakemake.input.items()), outputs=dict(snakemake.output.items()),
     stale=json.loads(snakemake.params.code)["stale"], captions=json.loads(snakemake.params.code)["captions"],
     log=snakemake.log[0])
