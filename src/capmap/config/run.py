"""The run configuration: validated once against the JSON schema (:mod:`capmap.config.parse`), then
frozen dataclasses. This module defines the run's type and how its document is read; it imports no
section module at run time, so that every job can rebuild its own fields (:mod:`capmap.config.typed`)
without depending on the code of the families it does not read."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from capmap.config.defaults import DEFAULT_CONFIG
from capmap.config.jobs import PlanTask
from capmap.config.typed import FILE
from capmap.config.validation import load_yaml
from capmap.errors import ConfigError

if TYPE_CHECKING:  # resolved lazily at run time through SECTION_TYPES
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
    from capmap.config.estimate import Estimate
    from capmap.config.failure import Failure
    from capmap.config.following import FollowConfig
    from capmap.config.reconfig import ReconfigConfig

__all__ = ["RunConfig", "SECTION_TYPES", "run_name", "run_document", "config_files", "NAMED_CONFIG", "DEFAULT_CONFIG"]

SECTION_TYPES = {  # a section type's name -> the module defining it (imported when a slice holds it)
    **dict.fromkeys(("DirectionsConfig", "LimitsConfig", "LockConfig", "PlanningConfig", "RefineConfig", "SamplingConfig",
                     "TaskConfig", "VerificationConfig"), "capmap.config.capacity"),
    "AdviceConfig": "capmap.config.advice", "AtlasConfig": "capmap.config.atlas", "BaselineConfig": "capmap.config.baseline",
    "DualArmConfig": "capmap.config.dualarm", "Estimate": "capmap.config.estimate",
    "Failure": "capmap.config.failure", "FollowConfig": "capmap.config.following", "ReconfigConfig": "capmap.config.reconfig",
}


@dataclass(frozen=True)
class RunConfig:
    """A whole run: the robot file and every section (``follow``, ``reconfig``, ``dualarm``: None when
    absent). ``failure`` (the resolved lock and start) and ``estimate`` (the map's size) are set by
    :func:`capmap.checks.check_run_config`. The sections' types are resolved lazily
    (:data:`SECTION_TYPES`): a job that rebuilds its slice imports only the sections it reads, so its
    code fingerprint does not follow every family's code."""

    robot: str = field(metadata=FILE)
    lock: LockConfig
    task: TaskConfig
    limits: LimitsConfig
    sampling: SamplingConfig
    directions: DirectionsConfig
    voxel_edge_m: float
    shards: int
    verification: VerificationConfig
    refine: RefineConfig | None  # None: voxels.refine false
    planning: PlanningConfig
    tasks: tuple[PlanTask, ...] = ()
    follow: FollowConfig | None = None
    reconfig: ReconfigConfig | None = None
    dualarm: DualArmConfig | None = None
    atlas: AtlasConfig | None = None
    baseline: BaselineConfig | None = None  # parse_config always sets it (absent section: its defaults)
    advice: AdviceConfig | None = None  # with an atlas (its maps): the section or its defaults
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


def _merged(base: dict, extra: dict) -> dict:
    """``base`` with ``extra`` merged in, mappings recursively (Snakemake's update_config)."""
    out = dict(base)
    for k, v in extra.items():
        out[k] = _merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


NAMED_CONFIG = "configfile"  # `--config configfile=my.yaml`: a config file only capmap's loader reads


def config_files(configfiles, overrides) -> tuple[list[str], dict]:
    """The config files of a workflow call and its other ``--config`` overrides: the file named by
    ``--config configfile=F`` (F only; with ``--configfile`` too, one line: two sources of one run), else
    the ``--configfile`` files."""
    overrides = dict(overrides or {})
    named = overrides.pop(NAMED_CONFIG, None)
    files = [str(f) for f in configfiles]
    if named is None:
        return files, overrides
    if files:
        raise ConfigError(f"--config {NAMED_CONFIG}={named} and --configfile {' '.join(files)}: give the run's config "
                          "one way")
    if not isinstance(named, str) or not named:
        raise ConfigError(f"--config {NAMED_CONFIG}: give a config file's path")
    return [named], overrides


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
