"""The run configuration: validated once against the JSON schema, then frozen dataclasses."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from capmap.config.atlas import AtlasConfig
from capmap.config.capacity import (
    DirectionsConfig,
    LimitsConfig,
    LockConfig,
    SamplingConfig,
    TaskConfig,
    VerificationConfig,
)
from capmap.config.dualarm import DualArmConfig
from capmap.config.estimate import Estimate
from capmap.config.failure import Failure
from capmap.config.following import FollowConfig
from capmap.config.reconfig import ReconfigConfig
from capmap.config.slices import payload_label
from capmap.config.validation import load_yaml, validate
from capmap.errors import ConfigError

__all__ = ["RunConfig", "parse_config", "load_config", "run_name"]


@dataclass(frozen=True)
class RunConfig:
    """A whole run: the robot file and every section (``follow``, ``reconfig``, ``dualarm``: None when
    absent). ``failure`` (the resolved lock and start) and ``estimate`` (the map's size) are set by
    :func:`capmap.config.check_run_config`."""

    robot: str
    lock: LockConfig
    task: TaskConfig
    limits: LimitsConfig
    sampling: SamplingConfig
    directions: DirectionsConfig
    voxel_edge_m: float
    shards: int
    verification: VerificationConfig
    follow: FollowConfig | None = None
    reconfig: ReconfigConfig | None = None
    dualarm: DualArmConfig | None = None
    atlas: AtlasConfig | None = None
    failure: Failure | None = None
    estimate: Estimate | None = None
    name: str = "default"


def run_name(doc: dict, source: str = "config") -> str:
    """The run's name, its folder under ``results/``: the config's ``run`` key, else the name of the
    (last) config file without its suffix ("my_lock95.yaml" -> "my_lock95"), else "default"."""
    if "run" in doc:
        return str(doc["run"])
    stem = re.sub(r"[^A-Za-z0-9_.-]", "_", Path(source.split(", ")[-1]).stem).lstrip("_.-")[:64]
    return stem if stem and source != "config" else "default"


def parse_config(doc: object, source: str = "config") -> RunConfig:
    """Validate a run-config mapping and turn it into a :class:`RunConfig`."""
    if not isinstance(doc, dict):
        raise ConfigError(f"{source}: the config must be a mapping of keys, got {type(doc).__name__}")
    validate(doc, "config", source)
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
        follow=FollowConfig.from_doc(doc["follow"]) if "follow" in doc else None,
        reconfig=ReconfigConfig.from_doc(doc["reconfig"]) if "reconfig" in doc else None,
        dualarm=dualarm,
        atlas=atlas,
        name=run_name(doc, source),
    )


def load_config(path: str | Path) -> RunConfig:
    return parse_config(load_yaml(path), str(path))
