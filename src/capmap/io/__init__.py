"""Input and output shared by every family: Parquet datasets with provenance and the
catalogue (:mod:`~capmap.io.datasets`), summary tables (:mod:`~capmap.io.tables`), logging
and one-line errors for the stages (:mod:`~capmap.io.logs`)."""

from capmap.io import datasets, logs, tables

__all__ = ["datasets", "logs", "tables"]
