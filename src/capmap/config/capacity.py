"""Config sections of the capacity-map family: lock, task, limits, sampling, directions,
voxels, verification. Frozen dataclasses built from the validated config document; the family's numerics
objects are built from them in :mod:`capmap.capacity.build`."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from capmap.config.typed import as_tuple
from capmap.errors import ConfigError

__all__ = ["LockConfig", "TaskConfig", "LimitsConfig", "SamplingConfig", "DirectionsConfig", "VerificationConfig",
           "RefineConfig", "PlanningConfig", "PLAN_MOVES", "TORQUE_FROM_CONFIG", "TORQUE_FROM_URDF"]

PLAN_MOVES = ("branch", "axis", "isotropic")  # planning.moves; the first is the default
MAX_DIRECTIONS = 1_000_000  # directions a set may be built from (the paper's grid before its duplicates go)


@dataclass(frozen=True)
class RefineConfig:
    """``voxels.refine`` (absent: these defaults; ``false``: no refinement, RunConfig.refine None):
    convergence tolerance, points per voxel (at least, at most, near a payload), the band around a
    payload, the seed of the refinement's random points."""

    rel_tol: float = 0.005
    min_points: int = 8
    max_points: int = 256
    near_band: float = 0.1
    near_min_points: int = 16
    seed: int = 0

    @classmethod
    def from_doc(cls, voxels_doc: dict) -> "RefineConfig | None":
        r = voxels_doc.get("refine", {})
        return None if r is False else cls(**r)


@dataclass(frozen=True)
class PlanningConfig:
    """``planning``: the kind of moves (``PLAN_MOVES``), the random tasks per payload of the
    plan_gain experiment, and the spacing of the samples a branch move is tracked at (None: the
    planner's own, :data:`capmap.capacity.branch_moves.TRACK_STEP_M`)."""

    moves: str = PLAN_MOVES[0]
    gain_tasks: int = 30
    track_step_m: float | None = None


DEFAULT_DT_S = 0.1  # verification.dt_s when not given


@dataclass(frozen=True)
class LockConfig:
    """``lock``: the failed joint (1-based) and the angle it is locked at (None: where it stood,
    see :mod:`capmap.config.failure`)."""

    joint: int
    angle_deg: float | None = None

    @classmethod
    def from_doc(cls, d: dict) -> "LockConfig":
        return cls(**d)


@dataclass(frozen=True)
class TaskConfig:
    """``task``: the fixed end-effector orientation, straight-line speed and acceleration limits,
    the payloads to plan and verify, start and goal positions (start None: where the end
    effector stood at q_ini), and the configuration when the joint failed."""

    orientation_rpy_deg: tuple[float, float, float]
    v_max_mps: float
    a_max_mps2: float
    payload_kg: tuple[float, ...]
    goal_m: tuple[float, float, float]
    q_ini_deg: tuple[float, ...]
    start_m: tuple[float, float, float] | None = None

    @classmethod
    def from_doc(cls, d: dict) -> "TaskConfig":
        task = {k: as_tuple(v) for k, v in d.items()}
        task["payload_kg"] = tuple(float(m) for m in np.atleast_1d(task["payload_kg"]))
        return cls(**task)


TORQUE_FROM_CONFIG = "config limits.joint_torque_nm"  # LimitsConfig.torque_limit_source
TORQUE_FROM_URDF = "urdf effort"


@dataclass(frozen=True)
class LimitsConfig:
    """``limits``: joint torque (one value or one per joint), base force and moment (one or three).
    Without ``limits.joint_torque_nm`` the joint torque limits are the URDF's ``<limit effort>`` of
    each joint (this is the key's default, filled in with the robot by :meth:`for_robot`);
    ``torque_limit_source`` says which (:data:`TORQUE_FROM_CONFIG` or :data:`TORQUE_FROM_URDF`)."""

    base_force_n: float | tuple[float, ...]
    base_moment_nm: float | tuple[float, ...]
    joint_torque_nm: float | tuple[float, ...] | None = None  # None until for_robot: the URDF's effort limits
    torque_limit_source: str = TORQUE_FROM_CONFIG

    @classmethod
    def from_doc(cls, d: dict) -> "LimitsConfig":
        out = {k: as_tuple(v) for k, v in d.items()}
        return cls(**out, torque_limit_source=TORQUE_FROM_CONFIG if "joint_torque_nm" in d else TORQUE_FROM_URDF)

    def for_robot(self, robot) -> "LimitsConfig":
        """The limits with the joint torque limits resolved: the config's, else the URDF effort limit of
        each joint of ``robot`` (:class:`capmap.core.robot.Robot`). A DH robot (no effort limits) or a
        joint whose effort limit is missing or zero, with no ``limits.joint_torque_nm``: one line
        naming the joint."""
        if self.joint_torque_nm is not None:
            return self
        src = robot.description.source
        if robot.effort_limit_nm is None:
            raise ConfigError(f"limits.joint_torque_nm is required: the robot file {src} gives DH rows, which carry "
                              "no joint effort limits (a URDF's <limit effort> would be the default)")
        for name, effort in zip(robot.joint_names, robot.effort_limit_nm):
            if not (np.isfinite(effort) and effort > 0):
                raise ConfigError(f"limits.joint_torque_nm is not given and {src}'s URDF "
                                  f"{robot.description.urdf_path.name} has {'no' if not np.isfinite(effort) else 'a zero'}"
                                  f" effort limit for joint {name}: give limits.joint_torque_nm (N m)")
        return replace(self, joint_torque_nm=tuple(float(e) for e in robot.effort_limit_nm))

    def torque_text(self) -> str:
        """The joint torque limits as text, e.g. ``87, 87, 87, 87, 12, 12, 12`` (N m) or ``700`` (every joint)."""
        tau = self.joint_torque_nm
        return "(not filled in)" if tau is None else ", ".join(f"{t:g}" for t in np.atleast_1d(tau))

    def describe(self) -> str:
        """The joint torque limits and where they come from, e.g. ``joint torque limits 87, ..., 12 N m
        (from urdf effort)``."""
        return f"joint torque limits {self.torque_text()} N m (from {self.torque_limit_source})"

    def canonical(self) -> "LimitsConfig":
        """The same limits with a list of equal values written as the one value (``[700] * 7`` and
        ``700`` are the same limits, so the same slices); call once the lengths are checked."""
        one = {k: (v[0] if isinstance(v, tuple) and v and all(x == v[0] for x in v) else v)
               for k, v in vars(self).items()}
        return LimitsConfig(**one)


@dataclass(frozen=True)
class SamplingConfig:
    """``sampling``: mode (joint | voxel_fill), joint-space samples, seed, jitter per voxel."""

    mode: str
    n_points: int
    seed: int
    jitter_per_voxel: int = 1

    @classmethod
    def from_doc(cls, d: dict) -> "SamplingConfig":
        return cls(**d)


@dataclass(frozen=True)
class DirectionsConfig:
    """``directions``: the whole sphere (exact: the minimum over every direction), the paper's grid
    (step_deg) or a near-uniform sphere (n)."""

    kind: str
    step_deg: float | None = None
    n: int | None = None

    @classmethod
    def from_doc(cls, d: dict) -> "DirectionsConfig":
        if d["kind"] == "paper_grid" and "step_deg" not in d:
            raise ConfigError("directions.step_deg is required for kind paper_grid")
        if d["kind"] == "sphere" and "n" not in d:
            raise ConfigError("directions.n is required for kind sphere")
        extra = {"paper_grid": ("n",), "sphere": ("step_deg",), "exact": ("n", "step_deg")}[d["kind"]]
        for key in extra:
            if key in d:
                raise ConfigError(f"directions.{key} does not apply to kind {d['kind']}")
        out = cls(**d)
        if out.kind == "exact":
            return out
        raw = np.ceil(360.0 / out.step_deg) ** 2 if out.kind == "paper_grid" else out.n
        if raw > MAX_DIRECTIONS:
            key = "directions.step_deg" if out.kind == "paper_grid" else "directions.n"
            raise ConfigError(f"{key} = {out.step_deg if out.kind == 'paper_grid' else out.n:g} gives {raw:.3g} "
                              f"directions to build (at most {MAX_DIRECTIONS:,}): "
                              f"{'raise' if out.kind == 'paper_grid' else 'lower'} {key}")
        return out


@dataclass(frozen=True)
class VerificationConfig:
    """``verification``: the largest sample spacing dt_s along a verified motion."""

    dt_s: float = DEFAULT_DT_S

    @classmethod
    def from_doc(cls, d: dict | None) -> "VerificationConfig":
        return cls(**(d or {}))
