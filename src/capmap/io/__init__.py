"""Input and output shared by every family: Parquet datasets with provenance (:mod:`~capmap.io.datasets`),
the catalogue and the API that reads a run's results (:mod:`~capmap.io.catalogue`), columns without
pandas (:mod:`~capmap.io.arrays`), summary tables (:mod:`~capmap.io.tables`), logging and one-line errors
for the stages (:mod:`~capmap.io.logs`), and the local run's job server that runs them warm
(:mod:`~capmap.io.job_server`, :mod:`~capmap.io.job_client`)."""

from capmap._lazy import lazy_exports

_EXPORTS = {"datasets": "datasets", "catalogue": "catalogue", "arrays": "arrays", "logs": "logs", "tables": "tables"}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
