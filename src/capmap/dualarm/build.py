"""The dual-arm family's one meeting of configuration and numerics: the ``dualarm`` section's data
(:mod:`capmap.config.dualarm`) in, the family's settings out (the scan, the envelope fit, the cost weights,
the augmented-Lagrangian loop, the unknown space, a job's horizon, inputs and planning settings), and the
dual-arm robot files read into robot descriptions and robots (one-line errors naming the file and key).
The defaults of the optional keys live in the numerics' settings classes; a key given in the config
overrides its default here."""

from __future__ import annotations

from dataclasses import fields, replace
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.config.dualarm import DualArmConfig, FitConfig, Horizon, ScanConfig, SolverConfig, UnknownConfig, WeightsConfig
from capmap.config.robot_file import check_meshes, check_urdf, package_file, urdf_package_dir
from capmap.config.validation import load_yaml
from capmap.dualarm.cloud_file import read_cloud
from capmap.dualarm.job import HorizonSteps, JobInputs, PlanSettings, assembly_on
from capmap.dualarm.ocp.assembly import Assembly
from capmap.dualarm.ocp.settings import ALSettings, Weights
from capmap.dualarm.scene.cloud import FitSettings
from capmap.dualarm.scene.robot import CapsuleGroup, DualArm, DualArmDescription, build_dual_arm
from capmap.dualarm.scene.solids import ScanSettings
from capmap.dualarm.scene.unknown import UnknownSettings
from capmap.dualarm.scene.unobserved import camera_suggestion
from capmap.dualarm.scene_file import load_scene
from capmap.dualarm.tables import capsules_from, envelope_from
from capmap.errors import CapmapError, ConfigError

__all__ = ["scan_settings", "fit_settings", "weights", "al_settings", "unknown_settings", "horizon_steps", "plan_settings",
           "stop_distance", "load_dual_arm_file", "build_robot", "robot_from", "job_inputs", "job_setup",
           "planning_error", "cloud_span_m", "MAX_FIT_CELLS"]

_ROBOT_KEYS = {"name", "description", "urdf", "arms", "locked", "capsules", "self_gap", "body_skip", "hold", "cover"}
_COVER = ("visual", "collision")


def _given(cfg) -> dict:
    """The fields of a config dataclass that the config gave (None: the numerics' default). A field not in
    the job's slice is passed on as it is (:class:`capmap.config.typed.Undeclared`: any use raises)."""
    return {f.name: v for f in fields(cfg) if (v := getattr(cfg, f.name)) is not None}


def scan_settings(cfg: ScanConfig) -> ScanSettings:
    """The scan's (or a user's cloud's) viewpoints (V, 3) m, spacing and noise."""
    return ScanSettings(np.asarray(cfg.viewpoints_m, dtype=float).reshape(-1, 3), float(cfg.spacing_m), float(cfg.noise_m))


def fit_settings(cfg: FitConfig) -> FitSettings:
    """The envelope fit's settings: the config's keys over the fit's defaults."""
    return FitSettings(**_given(cfg))


def weights(cfg: WeightsConfig) -> Weights:
    """The cost weights (control (14,)) and the collision margin (m)."""
    return Weights(np.asarray(cfg.control, dtype=float), float(cfg.velocity), float(cfg.panel), float(cfg.margin_m))


def al_settings(cfg: SolverConfig) -> ALSettings:
    """The augmented-Lagrangian loop's settings: the config's keys over the solver's defaults."""
    return ALSettings(**_given(cfg))


def unknown_settings(cfg: UnknownConfig) -> UnknownSettings:
    """The work volume (lower, upper (3,) m) and the carving voxel and near distance (m)."""
    return UnknownSettings(np.asarray(cfg.work_lower, dtype=float), np.asarray(cfg.work_upper, dtype=float),
                           **{k: v for k, v in _given(cfg).items() if k in ("voxel_m", "near_m")})


def horizon_steps(h: Horizon) -> HorizonSteps:
    """A horizon's nodes, step (s) and pre-insertion node."""
    return HorizonSteps(h.nodes, h.dt_s, h.pre_insertion_node)


def plan_settings(da: DualArmConfig) -> PlanSettings:
    """How the job's motion is planned: the horizon, cost weights, augmented-Lagrangian loop, finer grid and
    unknown space of the ``dualarm`` section."""
    return PlanSettings(horizon_steps(da.horizon), weights(da.weights), al_settings(da.solver), da.fine_factor,
                        unknown_settings(da.unknown))


def stop_distance(da: DualArmConfig) -> float:
    """How far short of each point a ray's free part stops (m): three noise sigmas (a user's cloud: its noise
    unknown, taken as 1 cm)."""
    return 3 * (da.scan.noise_m if da.cloud_file is None else 0.01)


def load_dual_arm_file(path: str | Path) -> DualArmDescription:
    """Read a dual-arm robot file; one-line errors naming the file and key."""
    path = Path(path)
    doc = load_yaml(path)
    src = str(path)
    if not isinstance(doc, dict):
        raise ConfigError(f"{src}: a robot file must be a mapping of keys, got {type(doc).__name__}")
    extra = sorted(set(doc) - _ROBOT_KEYS, key=str)
    if doc and len(extra) == len(doc):  # nothing of a dual-arm robot file: its keys are not echoed
        raise ConfigError(f"{src}: not a capmap dual-arm robot file: none of its keys is one of a dual-arm robot "
                          f"file's ({', '.join(sorted(_ROBOT_KEYS)[:6])}, ...)")
    if extra:
        raise ConfigError(f"{src}: unknown key {extra[0]} (allowed: {', '.join(sorted(_ROBOT_KEYS))})")
    for key in ("name", "urdf", "arms", "capsules"):
        if key not in doc:
            raise ConfigError(f"{src}: {key} is required in a dual-arm robot file")
    urdf = doc["urdf"]
    if "package" in urdf:
        urdf_path = package_file(urdf["package"], urdf["path"], src)
    else:
        urdf_path = (path.parent / urdf["path"]) if not Path(urdf["path"]).is_absolute() else Path(urdf["path"])
        if not urdf_path.is_file():
            raise ConfigError(f"{src}: urdf.path = {urdf['path']!r}: no such file")
    check_urdf(urdf_path, src)
    package_dir = urdf_package_dir(urdf_path)
    check_meshes(urdf_path, [package_dir], src)
    arms = doc["arms"]
    if sorted(arms) != ["left", "right"]:
        raise ConfigError(f"{src}: arms must be exactly 'left' and 'right' (found {sorted(arms)})")
    fingers = {}
    for side in ("left", "right"):
        if not isinstance(arms[side], dict) or len(arms[side].get("joints", [])) != 7 or "gripper" not in arms[side]:
            raise ConfigError(f"{src}: arms.{side} needs 7 joints and a gripper frame")
        extra = sorted(set(arms[side]) - {"joints", "gripper", "fingers"})
        if extra:
            raise ConfigError(f"{src}: arms.{side}: unknown key {extra[0]} (allowed: fingers, gripper, joints)")
        fl = arms[side].get("fingers", [])
        if not isinstance(fl, list) or any(not isinstance(f, dict) or sorted(f) != ["joint", "pad"]
                                           or not all(isinstance(v, str) for v in f.values()) for f in fl):
            raise ConfigError(f"{src}: arms.{side}.fingers must be a list of {{joint: <prismatic joint>, pad: <geometry "
                              "object>}} (the fingers closed on the held part's thickness)")
        fingers[side] = tuple((f["joint"], f["pad"]) for f in fl)
        clash = [j for j, _ in fingers[side] if j in doc.get("locked", {})]
        if clash:
            raise ConfigError(f"{src}: {clash[0]} is both a finger of arms.{side} (closed on the held part) and in "
                              "locked: give it in one place")
    groups = []
    for part in ("left", "right", "body"):
        for k, g in enumerate(doc["capsules"].get(part, [])):
            if "name" not in g or not g.get("geometry"):
                raise ConfigError(f"{src}: capsules.{part}[{k}] needs a name and a list of geometry")
            groups.append(CapsuleGroup(g["name"], tuple(g["geometry"]), part))
    names = [g.name for g in groups]
    if len(set(names)) != len(names):
        raise ConfigError(f"{src}: capsule names must be unique")
    cover = doc.get("cover", list(_COVER))
    if (not isinstance(cover, list) or not cover or any(c not in _COVER for c in cover)
            or len(set(cover)) != len(cover)):
        raise ConfigError(f"{src}: cover = {cover!r} must be a list of {' and/or '.join(_COVER)} (default both: the "
                          "capsules cover the visual meshes and the collision geometry)")
    return DualArmDescription(doc["name"], urdf_path, package_dir, {s: tuple(arms[s]["joints"]) for s in arms},
                              {s: arms[s]["gripper"] for s in arms}, {k: float(v) for k, v in doc.get("locked", {}).items()},
                              tuple(groups), int(doc.get("body_skip", 0)), int(doc.get("hold", 0)),
                              int(doc.get("self_gap", 2)), tuple(cover), fingers)


def build_robot(robot_file: str, scene_file: str) -> DualArm:
    """The robot of ``robot_file``, its fingers closed on the thickness of the panel of ``scene_file``."""
    try:
        return build_dual_arm(load_dual_arm_file(robot_file), float(load_scene(scene_file).panel.size[0]))
    except ConfigError:
        raise
    except CapmapError as exc:
        raise ConfigError(f"dualarm.robot = {robot_file!r}: {exc.in_terms(urdf='its URDF')}") from None


def robot_from(robot_file: str, capsules: pd.DataFrame) -> DualArm:
    """The robot with its capsules read back from their dataset, its locked joints (the fingers closed on
    the scene's panel) as the capsules were fitted with (their provenance); the visual meshes not loaded."""
    try:
        desc = replace(load_dual_arm_file(robot_file), locked=capsules.attrs["capmap"]["locked"], fingers={})
        robot = build_dual_arm(desc, visual=False)
    except ConfigError:
        raise
    except CapmapError as exc:
        raise ConfigError(f"dualarm.robot = {robot_file!r}: {exc.in_terms(urdf='its URDF')}") from None
    caps = capsules_from(capsules)
    return DualArm(robot.description, robot.model, robot.geometry, robot.gripper_frames, robot.q_lower, robot.q_upper,
                   robot.v_max, caps, robot.visual)


def job_inputs(da: DualArmConfig, environment: pd.DataFrame, capsules: pd.DataFrame) -> JobInputs:
    """(robot, envelope, its labels, scene) of a dual-arm job from its environment and capsules datasets: ``da``
    names the robot and scene files."""
    robot = robot_from(da.robot, capsules)
    env, labels = envelope_from(environment)
    return JobInputs(robot, env, labels, load_scene(da.scene))


def job_setup(da: DualArmConfig, environment: pd.DataFrame, capsules: pd.DataFrame, h: Horizon,
              boxes: np.ndarray | None = None) -> tuple[DualArm, Assembly]:
    """(robot, assembly) of a dual-arm job on horizon ``h`` (:func:`job_inputs`); ``boxes`` (B, 2, 3) m of
    unknown space join the environment."""
    inputs = job_inputs(da, environment, capsules)
    voxel = unknown_settings(da.unknown).voxel_m if boxes is not None and len(boxes) else None
    return inputs.robot, assembly_on(inputs, horizon_steps(h), boxes, voxel)


def planning_error(da: DualArmConfig, exc: CapmapError, inputs: JobInputs | None, boxes: np.ndarray | None
                   ) -> ConfigError:
    """An error of planning the job's motion in the config's terms: a key pose in collision, the scene's, or the
    cameras' (a box of unknown space: then where a camera would see it, from the job's ``inputs`` and unknown
    ``boxes`` (B, 2, 3) m, both read when a box is named)."""
    msg = exc.in_terms(scene=f"dualarm.scene = {da.scene!r}")
    if "unknown [" in msg:
        where = camera_suggestion(msg, unknown_settings(da.unknown), inputs.env, boxes,
                                  scan_settings(da.scan).viewpoints.mean(axis=0))
        msg += ("; that region (x, y, z ranges in m) was observed by no viewpoint of dualarm.cloud.viewpoints_m: "
                f"{where}, or move the task away from it")
    return ConfigError(msg)


MIN_FIT_POINTS = 10  # capmap.dualarm.scene.cloud.fit_envelope's least
MAX_FIT_CELLS = 2e8  # cells of the fit's patch grid (~5 bytes each: ~1 GB)


def cloud_span_m(da: DualArmConfig, scene_points: np.ndarray) -> float:
    """The largest extent (m) of the cloud the envelope job fits: a user's file read as the scan job reads
    it (its values checked: finite, not empty, viewpoint indices), else the scene's surface with the
    scan's noise (3 sigma each side). A synthetic scan noisier than its scene is one line naming
    ``dualarm.cloud.noise_m``; the fit's grid too large for memory one naming ``dualarm.fit.cell_m``."""
    if da.cloud_file is not None:
        pts, _ = read_cloud(da.cloud_file, len(da.scan.viewpoints_m))
        if len(pts) < MIN_FIT_POINTS:
            raise ConfigError(f"dualarm.cloud.file = {da.cloud_file!r}: {len(pts)} points; the envelope fit needs at "
                              f"least {MIN_FIT_POINTS}")
        span = float(np.ptp(pts, axis=0).max())
    else:
        scene_span = float(np.ptp(scene_points, axis=0).max())
        if not da.scan.noise_m <= scene_span:
            raise ConfigError(f"dualarm.cloud.noise_m = {da.scan.noise_m:g} m is larger than the scene it scans "
                              f"({scene_span:.3g} m across): a scan's noise is millimetres to centimetres")
        span = scene_span + 6 * da.scan.noise_m
    fit = fit_settings(da.fit)
    cells = (span / fit.cell_m + 1) ** 2
    if not cells <= MAX_FIT_CELLS:
        cloud = f"dualarm.cloud.file = {da.cloud_file!r}" if da.cloud_file is not None else "the synthetic scan"
        raise ConfigError(f"dualarm.fit.cell_m = {fit.cell_m:g} m: the fit's patch grid over {cloud}, {span:.3g} m across, "
                          f"would have {cells:.3g} cells (at most {MAX_FIT_CELLS:.0e}, ~1 GB): raise dualarm.fit.cell_m")
    return span
