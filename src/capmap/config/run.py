"""The run configuration: validated once against the JSON schema, then frozen dataclasses."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from capmap.config.atlas import AtlasConfig
from capmap.config.capacity import (
    DirectionsConfig,
    LimitsConfig,
    LockConfig,
    PlanningConfig,
    PlanTask,
    RefineConfig,
    SamplingConfig,
    TaskConfig,
    VerificationConfig,
    payload_label,
)
from capmap.config.dualarm import DualArmConfig
from capmap.config.estimate import Estimate
from capmap.config.failure import Failure
from capmap.config.following import FollowConfig
from capmap.config.reconfig import ReconfigConfig
from capmap.config.typed import FILE
from capmap.config.validation import load_yaml, validate
from capmap.errors import ConfigError

__all__ = ["RunConfig", "parse_config", "load_config", "run_name", "run_document", "DEFAULT_CONFIG"]

DEFAULT_CONFIG = "config/config.yaml"  # the config when no --configfile is given


@dataclass(frozen=True)
class RunConfig:
    """A whole run: the robot file and every section (``follow``, ``reconfig``, ``dualarm``: None when
    absent). ``failure`` (the resolved lock and start) and ``estimate`` (the map's size) are set by
    :func:`capmap.config.check_run_config`."""

    robot: str = field(metadata=FILE)
    lock: LockConfig
    task: TaskConfig
    limits: LimitsConfig
    sampling: SamplingConfig
    directions: DirectionsConfig
    voxel_edge_m: float
    shards: int
    verification: VerificationConfig
    refine: RefineConfig | None = RefineConfig()
    planning: PlanningConfig = PlanningConfig()
    tasks: tuple[PlanTask, ...] = ()
    follow: FollowConfig | None = None
    reconfig: ReconfigConfig | None = None
    dualarm: DualArmConfig | None = None
    atlas: AtlasConfig | None = None
    failure: Failure | None = None
    estimate: Estimate | None = None
    name: str = "default"


def run_name(doc: dict, source: str = "config") -> str:
    """The run's name, its folder under ``results/``: the config's ``run`` key, else the name of the
    (last) config file without its suffix ("my_lock95.yaml" -> "my_lock95", other characters as "_": "my lock.yaml"
    -> "my_lock"); "default" only without a config file (``source`` "config"). A file name with nothing usable
    (``_.yaml``, ``测试.yaml``) is a ConfigError asking for ``run:``: it must not share results/default/."""
    if "run" in doc:
        return str(doc["run"])
    if source == "config":
        return "default"
    last = source.split(", ")[-1]
    stem = re.sub(r"[^A-Za-z0-9_.-]", "_", Path(last).stem).lstrip("_.-")[:64]
    if not stem:
        raise ConfigError(f"{last if last.isprintable() else repr(last)}: its file name gives no run name (letters, "
                          "digits, _ . -) for results/<run>/; add a line `run: <name>` to it")
    return stem


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
    try:
        refine = RefineConfig.from_doc(doc["voxels"])
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
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
        refine=refine,
        planning=PlanningConfig(**doc.get("planning", {})),
        tasks=tuple(PlanTask.from_doc(t) for t in doc.get("tasks") or ()),
        follow=FollowConfig.from_doc(doc["follow"]) if "follow" in doc else None,
        reconfig=ReconfigConfig.from_doc(doc["reconfig"]) if "reconfig" in doc else None,
        dualarm=dualarm,
        atlas=atlas,
        name=run_name(doc, source),
    )


def _merged(base: dict, extra: dict) -> dict:
    """``base`` with ``extra`` merged in, mappings recursively (Snakemake's update_config)."""
    out = dict(base)
    for k, v in extra.items():
        out[k] = _merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def run_document(configfiles: list[str], overrides: dict | None = None) -> dict:
    """The run's config document as capmap reads it: each config file (``configfiles``, else the
    default config) through :func:`~capmap.config.validation.load_yaml` (bounded, no templates, no
    duplicate keys), merged in order as Snakemake merges them, then the ``--config`` overrides."""
    doc: dict = {}
    for f in configfiles or [DEFAULT_CONFIG]:
        part = load_yaml(f)
        if not isinstance(part, dict):
            raise ConfigError(f"{f}: empty or not a mapping of keys")
        doc = _merged(doc, part)
    return _merged(doc, overrides or {})


def load_config(path: str | Path) -> RunConfig:
    return parse_config(load_yaml(path), str(path))
