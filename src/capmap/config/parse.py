"""Parsing a run's config document: JSON-schema validation, then the section parsers into a
:class:`~capmap.config.run.RunConfig` (used before any job; jobs rebuild their slices instead)."""

from __future__ import annotations

from pathlib import Path

from capmap.config.advice import AdviceConfig
from capmap.config.atlas import AtlasConfig
from capmap.config.baseline import BaselineConfig
from capmap.config.capacity import (
    DirectionsConfig,
    LimitsConfig,
    LockConfig,
    PlanningConfig,
    RefineConfig,
    SamplingConfig,
    TaskConfig,
    VerificationConfig,
)
from capmap.config.dualarm import DualArmConfig
from capmap.config.following import FollowConfig
from capmap.config.jobs import PlanTask, payload_label
from capmap.config.reconfig import ReconfigConfig
from capmap.config.run import RunConfig, run_name
from capmap.config.validation import load_yaml, validate
from capmap.errors import ConfigError

__all__ = ["parse_config", "load_config"]


def parse_config(doc: object, source: str = "config") -> RunConfig:
    """Validate a run-config mapping and turn it into a :class:`RunConfig`."""
    if not isinstance(doc, dict):
        raise ConfigError(f"{source}: the config must be a mapping of keys, got {type(doc).__name__}")
    doc = validate(doc, "config", source)  # integral floats as ints where the schema says integer
    try:
        directions = DirectionsConfig.from_doc(doc["directions"])
        dualarm = DualArmConfig.from_doc(doc["dualarm"]) if "dualarm" in doc else None
        atlas = AtlasConfig.from_doc(doc["atlas"]) if "atlas" in doc else None
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    task = TaskConfig.from_doc(doc["task"])
    labels = [payload_label(m) for m in task.payload_kg]
    if len(set(labels)) != len(labels):
        raise ConfigError(f"{source}: task.payload_kg has repeated values {labels}")
    return RunConfig(
        robot=doc["robot"],
        lock=LockConfig.from_doc(doc["lock"]),
        task=task,
        limits=LimitsConfig.from_doc(doc["limits"]),
        sampling=SamplingConfig.from_doc(doc["sampling"]),
        directions=directions,
        voxel_edge_m=float(doc["voxels"]["edge_m"]),
        shards=int(doc["shards"]),
        verification=VerificationConfig.from_doc(doc.get("verification")),
        refine=RefineConfig.from_doc(doc["voxels"]),  # its point counts checked with the robot (check_run_config)
        planning=PlanningConfig(**doc.get("planning", {})),
        tasks=tuple(PlanTask.from_doc({"q_start_deg": doc["task"]["q_ini_deg"], **t}) for t in doc.get("tasks") or ()),
        follow=FollowConfig.from_doc(doc["follow"]) if "follow" in doc else None,
        reconfig=ReconfigConfig.from_doc(doc["reconfig"]) if "reconfig" in doc else None,
        dualarm=dualarm,
        atlas=atlas,
        baseline=BaselineConfig.from_doc(doc.get("baseline")),
        advice=AdviceConfig.from_doc(doc.get("advice")) if atlas is not None else None,  # its maps: the atlas'
        name=run_name(doc, source),
    )


def load_config(path: str | Path) -> RunConfig:
    return parse_config(load_yaml(path), str(path))
