"""The dual-arm family's one meeting of configuration and numerics: the ``dualarm`` section's data
(:mod:`capmap.config.dualarm`) in, the family's settings out (the scan, the envelope fit, the cost weights,
the augmented-Lagrangian loop, the unknown space), and the dual-arm robot files read into robot
descriptions (one-line errors naming the file and key). The defaults of the optional keys live in the
numerics' settings classes; a key given in the config overrides its default here."""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import numpy as np

from capmap.config.dualarm import FitConfig, ScanConfig, SolverConfig, UnknownConfig, WeightsConfig
from capmap.config.robot_file import check_meshes, check_urdf, package_file, urdf_package_dir
from capmap.config.validation import load_yaml
from capmap.dualarm.ocp.settings import ALSettings, Weights
from capmap.dualarm.scene.cloud import FitSettings
from capmap.dualarm.scene.robot import CapsuleGroup, DualArmDescription
from capmap.dualarm.scene.solids import ScanSettings
from capmap.dualarm.scene.unknown import UnknownSettings
from capmap.errors import ConfigError

__all__ = ["scan_settings", "fit_settings", "weights", "al_settings", "unknown_settings", "load_dual_arm_file"]

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


def load_dual_arm_file(path: str | Path) -> DualArmDescription:
    """Read a dual-arm robot file; one-line errors naming the file and key."""
    path = Path(path)
    doc = load_yaml(path)
    src = str(path)
    if not isinstance(doc, dict):
        raise ConfigError(f"{src}: a robot file must be a mapping of keys, got {type(doc).__name__}")
    extra = sorted(set(doc) - _ROBOT_KEYS)
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
