"""Stages: the functions the Snakemake scripts call, one per rule. File I/O lives here (and in
:mod:`capmap.io`) only; each stage reads its inputs, calls the numerics of its family,
writes Parquet with provenance, and logs its progress.

- :mod:`~capmap.stages.capacity`   model, sample, capacity (sharded), voxels, summary
- :mod:`~capmap.stages.verify`     plan, verify, verify_plots (one job per payload)
- :mod:`~capmap.stages.following`  follow, follow_plots (one job per case)
- :mod:`~capmap.stages.refine`     refine (sharded: all branches and each configuration), voxel_map
- :mod:`~capmap.stages.report`     catalogue, concatenated summaries
- :mod:`~capmap.stages.query`      ``capmap query``: a point on every configuration, a line on one
- :mod:`~capmap.stages.query_service` a warm process that answers ``capmap query`` in a third of a second
"""

__all__ = ["capacity", "common", "following", "query", "refine", "report", "verify"]
