"""What every stage does first: rebuild its typed configuration from its rule's params (the
canonical JSON of its slice; see :mod:`capmap.config.slices`)."""

from __future__ import annotations

from collections.abc import Mapping

from capmap.config.slices import StageConfig, stage_config

__all__ = ["StageConfig", "stage_config", "Outputs"]

Outputs = Mapping[str, str]  # a job's output files by the names its rule gives them (the script passes them all)
