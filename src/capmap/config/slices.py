"""Stage slices: the fields of the validated run configuration each stage reads.

Every stage declares, in :data:`STAGES`, the fields of :class:`~capmap.config.run.RunConfig` it
reads (dotted paths; ``job.*`` for the fields of the one plan/verify job it runs, a
:class:`~capmap.config.capacity.PlanTask`) and the stages it comes after. Its slice is derived from
those declarations alone (:func:`stage_slice`): the values of its own fields and of every earlier
stage's, as JSON (:func:`capmap.config.typed.to_doc`), plus the content hashes of every file those
fields name (robot, scene and cloud files, the URDFs and meshes they name). The slice's canonical
JSON is the rule's ``params`` (a change reruns exactly the stages that read it) and each output's
provenance. The job gets the same types back with :func:`stage_config` (one generic rebuild; a
field it did not declare raises when used).

A key's path: YAML -> schema validation -> the section dataclass (``LockConfig``) -> resolved
(``Failure``) in :func:`capmap.checks.check_run_config` -> :func:`stage_slice` -> the
rule's params -> :func:`stage_config` in the job -> the numerics.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

from capmap.config.jobs import PlanTask, payload_label
from capmap.config.robot_file import referenced_files
from capmap.config.run import SECTION_TYPES, RunConfig
from capmap.config.typed import file_paths as _file_fields
from capmap.config.typed import get_path, partial, rounded, to_doc
from capmap.errors import CapmapError
from capmap.io.datasets import canonical, config_hash
from capmap.io.fingerprint import file_fingerprints

__all__ = ["Stage", "STAGES", "StageConfig", "stage_slice", "stage_config", "upstream_fields", "section_modules",
           "canonical", "config_hash", "payload_label", "files_of"]


@dataclass(frozen=True)
class Stage:
    """What a stage reads: ``fields`` (dotted paths, or a function of the config giving them, for
    fields read only in some modes) and the stages whose outputs it reads (``after``)."""

    fields: tuple[str, ...] | Callable[[RunConfig], tuple[str, ...]]
    after: tuple[str, ...] = ()


def _sample(cfg: RunConfig) -> tuple[str, ...]:  # voxel_fill fills the voxels of the map's grid
    return ("failure.joint", "failure.angle_deg", "sampling") + (
        ("voxel_edge_m",) if cfg.sampling.mode == "voxel_fill" else ())


def _refine(cfg: RunConfig) -> tuple[str, ...]:  # voxels near any task payload are refined further
    return ("refine",) + (("task.payload_kg",) if cfg.refine is not None else ())


def _plan(cfg: RunConfig) -> tuple[str, ...]:  # moves on the executed branch start from its configuration
    return ("job.payload_kg", "job.start_m", "job.goal_m", "planning.moves") + (
        ("job.q_start_deg", "planning.track_step_m") if cfg.planning.moves == "branch" else ())


_RECONFIG = ("robot", "capture", "unlock", "configuration_deg", "theta_deg", "d_m", "duration_s", "dt_s",
             "joint_rate_limit_deg_s", "min_time_scale")
_TASK_MOTION = ("task.orientation_rpy_deg", "task.v_max_mps", "task.a_max_mps2")


def _baseline_shard(cfg: RunConfig) -> tuple[str, ...]:  # the healthy arm on the failed map's lattice
    return ("robot", "failure.joint", "failure.angle_deg", "sampling", "voxel_edge_m", "limits", "directions",
            "baseline.step_deg", "baseline.screen_directions", "baseline.polish_levels") + _TASK_MOTION + _refine(cfg)


STAGES: dict[str, Stage] = {
    # family 1: capacity map -> plan -> verify
    "model": Stage(("robot",)),
    "sample": Stage(_sample, ("model",)),
    "capacity": Stage(_TASK_MOTION + ("limits", "directions"), ("sample",)),
    "voxels": Stage(("voxel_edge_m",), ("capacity",)),
    "refine": Stage(_refine, ("voxels",)),
    # the map's figures: of the arm's configuration at the start, with the planned paths
    "view": Stage(("failure.start_m", "failure.q_start_deg", "task.goal_m", "task.payload_kg"), ("refine",)),
    "plan": Stage(_plan, ("refine",)),
    "verify": Stage(("job", "verification.dt_s"), ("plan",)),
    "gain": Stage(("task.payload_kg", "planning.gain_tasks", "verification.dt_s"), ("refine",)),
    "atlas_map": Stage(("robot", "limits", "verification.dt_s", "atlas.sampling", "atlas.directions", "atlas.edge_m",
                        "failure.start_m")  # the start (given or FK(q_ini)) does not depend on the lock
                       + _TASK_MOTION + tuple(f"task.{k}" for k in ("payload_kg", "goal_m", "q_ini_deg"))),
    "atlas": Stage(("atlas",), ("atlas_map",)),
    # the lock-angle advice: one lock sweep per joint (its angle where it stands: a param), the run's tasks verified
    # at every swept angle (each from its start, its start configuration the reference), the failure-tolerant map
    "lock_sweep": Stage(("robot", "limits", "directions", "atlas.sampling", "atlas.edge_m", "advice.step_deg")
                        + _TASK_MOTION),
    "advice_tasks": Stage(("failure.start_m", "task.goal_m", "task.payload_kg", "task.q_ini_deg", "tasks",
                           "verification.dt_s"), ("lock_sweep",)),
    "advice": Stage(("advice.step_deg",), ("advice_tasks",)),
    "tolerant": Stage(("task.payload_kg", "failure.start_m", "task.goal_m"), ("lock_sweep",)),
    # the healthy arm and the failure's cost (reads the failed map: its worst points, its values)
    "baseline_shard": Stage(_baseline_shard, ("refine",)),
    "baseline": Stage(("baseline.check_voxels", "baseline.check_step_deg"), ("baseline_shard", "view")),
    # family 2: following (space: the verified path of its payload, not the verification's sampling)
    "follow_space": Stage(("job", "follow.period_s", "follow.store_period_s", "follow.space"), ("plan",)),
    "follow_ground": Stage(("follow.period_s", "follow.store_period_s", "follow.ground")),
    # family 3: reconfiguration
    "reconfig_pinv": Stage(tuple(f"reconfig.{k}" for k in _RECONFIG)),
    "reconfig_nullspace": Stage(("reconfig.kappa0",), ("reconfig_pinv",)),
    "reconfig_animation": Stage(("reconfig.animation_fps",), ("reconfig_nullspace",)),
    # family 4: dual-arm assembly
    "dualarm_scan": Stage(tuple(f"dualarm.{k}" for k in ("scene", "cloud_file", "scan", "scan_seed"))),
    "dualarm_envelope": Stage(("dualarm.fit", "dualarm.fit_seed"), ("dualarm_scan",)),
    "dualarm_capsules": Stage(("dualarm.robot", "dualarm.scene")),  # the fingers close on the scene's panel
    "dualarm_problem": Stage(tuple(f"dualarm.{k}" for k in ("weights.control", "weights.velocity", "weights.panel",
                                                             "solver")), ("dualarm_envelope", "dualarm_capsules")),
    "dualarm_unknown": Stage(tuple(f"dualarm.unknown.{k}" for k in ("work_lower", "work_upper", "voxel_m")),
                             ("dualarm_envelope",)),
    "dualarm_optimise": Stage(("dualarm.weights.margin_m", "dualarm.horizon", "dualarm.fine_factor", "dualarm.unknown"),
                              ("dualarm_problem", "dualarm_unknown")),
    "dualarm_check": Stage(("dualarm.check",), ("dualarm_problem",)),
    "dualarm_animation": Stage(("dualarm.animation_fps",), ("dualarm_optimise",)),
}


def upstream_fields(cfg: RunConfig, stage: str) -> tuple[str, ...]:
    """Every field ``stage`` depends on: its own and those of every stage it comes after."""
    st = STAGES[stage]
    own = st.fields(cfg) if callable(st.fields) else st.fields
    seen = dict.fromkeys(p for before in st.after for p in upstream_fields(cfg, before))
    return tuple(dict.fromkeys([*seen, *own]))


@lru_cache(maxsize=None)
def files_of(path: str) -> dict[str, str]:
    """Content fingerprints of a robot/scene/cloud file and of the files it names (URDF, meshes):
    an edited file reruns its stages even with an old date."""
    return file_fingerprints([f for f in referenced_files(path) if f.is_file()])


def _put(doc: dict, path: str, value) -> None:
    *parents, leaf = path.split(".")
    for name in parents:
        doc = doc.setdefault(name, {})
    doc[leaf] = value


def stage_slice(cfg: RunConfig, stage: str, job: PlanTask | None = None) -> dict:
    """The slice of ``stage``: ``{"run": {...}, "job": {...}, "files": {...}}`` with the declared
    fields' values (``job`` only when the stage reads one) and the content hashes of the files they
    name. ``cfg`` is the checked configuration (:func:`capmap.checks.check_run_config`)."""
    out: dict = {}
    files: dict[str, str] = {}
    for path in upstream_fields(cfg, stage):
        is_job = path == "job" or path.startswith("job.")
        if is_job and job is None:
            raise CapmapError(f"stage {stage} reads {path}: give its job (a PlanTask)")
        root, key, sub = (job, "job", path[4:]) if is_job else (cfg, "run", path)
        value, meta, absent = get_path(root, sub) if sub else (root, {}, "")
        if absent:  # a section the config does not have: the job sees None, not a phantom section
            _put(out.setdefault(key, {}), absent, None)
            continue
        doc = rounded(to_doc(value), meta)
        if sub:
            _put(out.setdefault(key, {}), sub, doc)
        else:
            out[key] = doc
        for f in _file_fields(value, meta):
            files.update(files_of(f))
    if files:
        out["files"] = dict(sorted(files.items()))
    return out


def section_modules(sl: dict) -> list[str]:
    """The config modules whose types a job rebuilds from its slice ``sl`` (the sections it holds):
    their code is part of the job's code fingerprint, as the modules its script imports are."""
    names = set()
    for name in sl.get("run", {}):
        ann = RunConfig.__dataclass_fields__[name].type
        names |= set(re.findall(r"\w+", str(ann))) & set(SECTION_TYPES)
    return sorted({SECTION_TYPES[t] for t in names})


@dataclass(frozen=True)
class StageConfig:
    """What a job receives: the run configuration with the fields of its slice (every other field
    :class:`~capmap.config.typed.Undeclared`), its plan/verify ``job`` (or None), and the slice as
    parsed JSON (``doc``: its provenance)."""

    run: RunConfig
    job: PlanTask | None
    doc: dict


def stage_config(slice_json: str) -> StageConfig:
    """Rebuild a job's typed configuration from its rule's params (canonical JSON of the slice)."""
    doc = json.loads(slice_json)
    job = doc.get("job")
    return StageConfig(run=partial(RunConfig, doc.get("run", {})),
                       job=None if job is None else partial(PlanTask, job, "job"), doc=doc)
