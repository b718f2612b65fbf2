"""Config section of the dual-arm family (``dualarm``) and its robot file format.

A dual-arm robot file names a URDF (a path relative to the file, or a file shipped by a pip
package), the two arms' joints and gripper frames, the joints to lock and their values, and
the capsule groups (URDF geometry objects each capsule covers), ``cover`` (the URDF models the
capsules cover: visual and/or collision, default both) and the self-collision rules ``self_gap``,
``body_skip`` and ``hold`` (see :mod:`capmap.dualarm.ocp.assembly`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from capmap.config.robot_file import check_meshes, check_urdf, package_file, urdf_package_dir
from capmap.config.typed import FILE
from capmap.config.validation import load_yaml
from capmap.dualarm.ocp.settings import ALSettings, Weights
from capmap.dualarm.scene.cloud import FitSettings
from capmap.dualarm.scene.robot import CapsuleGroup, DualArmDescription
from capmap.dualarm.scene.solids import ScanSettings
from capmap.dualarm.scene.unknown import UnknownSettings
from capmap.errors import ConfigError

__all__ = ["DualArmConfig", "Horizon", "load_dual_arm_file", "cloud_source", "fit_settings", "horizon", "CheckSettings",
           "unknown_settings",
           "check_settings",
           "weights"]

_ROBOT_KEYS = {"name", "description", "urdf", "arms", "locked", "capsules", "self_gap", "body_skip", "hold", "cover"}
_COVER = ("visual", "collision")


@dataclass(frozen=True)
class Horizon:
    """nodes N (N + 1 states), step dt_s, the node of the pre-insertion pose."""

    nodes: int
    dt_s: float
    pre_insertion_node: int


@dataclass(frozen=True)
class CheckSettings:
    """The CSQP cross-check: its horizon, SQP iteration limit and KKT tolerance (CSQP's own
    criterion, whose dual part is only as accurate as its inner ADMM QP solves), and the tighter
    tolerance of the AL-FDDP solve it is compared with."""

    horizon: Horizon
    max_iterations: int = 100
    tolerance: float = 1e-6
    al_tolerance: float = 1e-9


@dataclass(frozen=True)
class DualArmConfig:
    """``dualarm``: robot and scene files, the cloud (a file, or a synthetic scan), fitting
    overrides, the horizon, cost weights, the safety margin, solver settings, the CSQP check's
    horizon, the re-check's refinement and the animation's frame rate."""

    robot: str = field(metadata=FILE)
    scene: str = field(metadata=FILE)
    cloud_file: str | None = field(metadata=FILE)
    scan: ScanSettings | None  # a user's cloud: its viewpoints here too (spacing and noise unused)
    scan_seed: int
    fit: FitSettings
    fit_seed: int
    horizon: Horizon
    weights: Weights
    solver: ALSettings
    check: CheckSettings
    unknown: UnknownSettings
    fine_factor: int = 5  # the defaults of dualarm.fine_factor and dualarm.animation_fps
    animation_fps: float = 25.0

    @classmethod
    def from_doc(cls, d: dict) -> "DualArmConfig":
        """The whole section (every key a job might read; see the piece builders below)."""
        cloud_file, scan, scan_seed = cloud_source(d)
        fit, fit_seed = fit_settings(d)
        return cls(robot=d["robot"], scene=d["scene"], cloud_file=cloud_file, scan=scan, scan_seed=scan_seed, fit=fit,
                   fit_seed=fit_seed, horizon=horizon(d), weights=weights(d), solver=ALSettings(**d["solver"]),
                   check=check_settings(d), unknown=unknown_settings(d),
                   **{k: d[k] for k in ("fine_factor", "animation_fps") if k in d})


# --------------------------------------------------------------------------- the section's pieces (from the YAML)


def cloud_source(d: dict) -> tuple[str | None, ScanSettings | None, int]:
    """``dualarm.cloud``: (the user's file, its viewpoints (spacing and noise 0), 0) or (None, the scan's
    settings, its seed)."""
    cloud = d["cloud"]
    if "file" in cloud:
        extra = sorted(set(cloud) - {"file", "viewpoints_m"})
        if extra:
            raise ConfigError(f"dualarm.cloud: give either file (and the viewpoints_m it was taken from) or a synthetic "
                              f"scan (viewpoints_m, spacing_m, noise_m, seed), not both (found {extra[0]} with file)")
        if "viewpoints_m" not in cloud:
            raise ConfigError("dualarm.cloud.viewpoints_m is required with dualarm.cloud.file: the cameras' positions "
                              "tell observed free space from space no camera saw (which is taken as occupied)")
        return cloud["file"], ScanSettings(np.asarray(cloud["viewpoints_m"], float), 0.0, 0.0), 0
    missing = [k for k in ("viewpoints_m", "spacing_m", "noise_m", "seed") if k not in cloud]
    if missing:
        raise ConfigError(f"dualarm.cloud.{missing[0]} is required for a synthetic scan (or give dualarm.cloud.file)")
    scan = ScanSettings(np.asarray(cloud["viewpoints_m"], float), float(cloud["spacing_m"]), float(cloud["noise_m"]))
    return None, scan, int(cloud["seed"])


def unknown_settings(d: dict) -> UnknownSettings:
    """``dualarm.unknown``."""
    u = d["unknown"]
    box = np.array([u["work_volume_m"][ax] for ax in ("x_m", "y_m", "z_m")], dtype=float)
    if not (box[:, 0] < box[:, 1]).all():
        raise ConfigError(f"dualarm.unknown.work_volume_m = {u['work_volume_m']}: each lower bound must be < its upper")
    return UnknownSettings(box[:, 0], box[:, 1], **{k: float(u[k]) for k in ("voxel_m", "near_m") if k in u})


def fit_settings(d: dict) -> tuple[FitSettings, int]:
    """``dualarm.fit`` over the defaults, and its RANSAC seed."""
    fit = dict(d.get("fit", {}))
    seed = int(fit.pop("seed", 0))
    return FitSettings(**fit), seed


def _horizon(key: str, h: dict) -> Horizon:
    out = Horizon(int(h["nodes"]), float(h["dt_s"]), int(h["pre_insertion_node"]))
    if not 0 < out.pre_insertion_node < out.nodes:
        raise ConfigError(f"dualarm.{key}.pre_insertion_node = {out.pre_insertion_node} must lie between 0 and "
                          f"dualarm.{key}.nodes = {out.nodes}")
    return out


def horizon(d: dict) -> Horizon:
    """``dualarm.horizon``."""
    return _horizon("horizon", d["horizon"])


def check_settings(d: dict) -> CheckSettings:
    """``dualarm.check``."""
    c = d["check"]
    return CheckSettings(_horizon("check", c), **{k: c[k] for k in ("max_iterations", "tolerance", "al_tolerance")
                                                   if k in c})  # else CheckSettings' defaults


def weights(d: dict) -> Weights:
    """``dualarm.weights`` and ``dualarm.margin_m``."""
    w = d["weights"]
    control = np.broadcast_to(np.asarray(w["control"], float), (14,)).copy()
    return Weights(control, float(w["velocity"]), float(w["panel"]), float(d["margin_m"]))


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
