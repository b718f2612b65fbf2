"""Robot files (YAML, degrees) -> :class:`capmap.core.robot.RobotDescription` (SI, radians) -> robots.

Schema: ``capmap/config/schemas/robot.schema.json``. A robot is given either by DH rows
(modified/Craig or standard) with per-link mass, centre of mass and inertia, or by a URDF
file (a path relative to the robot file, or a file shipped by a pip package), with the URDF
joints to hold fixed (``locked``: name -> value, rad or m) and optionally the arm's joints
(``joints``, root first). Every problem is one :class:`capmap.errors.ConfigError` line naming
the file and the key. The files a robot file names (URDF, meshes) and their checks:
:mod:`capmap.config.robot_file`. Every family's build module loads its robots here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from capmap.config.robot_file import check_urdf, package_file
from capmap.config.run import RunConfig
from capmap.config.validation import load_yaml, validate
from capmap.core.ik import classify
from capmap.core.reduction import LockedArm, free, lock
from capmap.core.robot import Drive, LinkInertia, Robot, RobotDescription, build_robot
from capmap.errors import CapmapError, ConfigError

__all__ = ["lock_classes", "parse_robot", "load_robot", "load", "transform", "locked_arm", "run_arm"]


def _inertia_matrix(values: list[float], where: str) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if len(v) == 3:
        inertia = np.diag(v)
    elif len(v) == 6:
        ixx, iyy, izz, ixy, ixz, iyz = v
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    else:
        raise ConfigError(f"{where}: expected 3 (principal) or 6 values, got {len(v)}")
    eig = np.linalg.eigvalsh(inertia)
    if eig.min() <= 0:
        raise ConfigError(f"{where}: inertia is not positive definite (eigenvalues {np.round(eig, 6).tolist()})")
    a, b, c = np.sort(eig)
    if a + b < c * (1 - 1e-9):
        raise ConfigError(f"{where}: principal moments {np.round(eig, 6).tolist()} violate the triangle "
                          "inequality (no rigid body has them)")
    return inertia


def transform(xyz, rpy_deg) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(*np.deg2rad(rpy_deg))
    T[:3, 3] = xyz
    return T


def _drive(entry: dict, joint: int | str, where: str) -> Drive:
    """One ``drives`` entry (validated by the schema: non-negative finite numbers) -> :class:`Drive`."""
    if "armature_kgm2" in entry and ("rotor_inertia_kgm2" in entry or "gear_ratio" in entry):
        raise ConfigError(f"{where}: give armature_kgm2 or rotor_inertia_kgm2 with gear_ratio, not both")
    if ("rotor_inertia_kgm2" in entry) != ("gear_ratio" in entry):
        raise ConfigError(f"{where}: rotor_inertia_kgm2 and gear_ratio go together (armature = rotor inertia x "
                          "gear ratio^2)")
    armature = entry.get("armature_kgm2")
    if "rotor_inertia_kgm2" in entry:
        with np.errstate(over="ignore"):
            armature = float(np.float64(entry["rotor_inertia_kgm2"]) * np.float64(entry["gear_ratio"]) ** 2)
        if not np.isfinite(armature):
            raise ConfigError(f"{where}: rotor_inertia_kgm2 x gear_ratio^2 = {entry['rotor_inertia_kgm2']:g} x "
                              f"{entry['gear_ratio']:g}^2 overflows a float64 (the reflected inertia must be finite)")
    friction = entry.get("friction", {})
    return Drive(joint, None if armature is None else float(armature),
                 None if "coulomb_nm" not in friction else float(friction["coulomb_nm"]),
                 None if "viscous_nms" not in friction else float(friction["viscous_nms"]))


def _drives(doc: dict, source: str, n: int | None) -> tuple[Drive, ...]:
    """The ``drives`` of a robot document: a list of n for a DH robot (n joints), a mapping joint name ->
    drive for a URDF robot (n None: the names are checked when the model is built)."""
    if "drives" not in doc:
        return ()
    drives = doc["drives"]
    if n is not None:
        if not isinstance(drives, list):
            raise ConfigError(f"{source}: drives: a DH robot's drives are a list, one per joint (a mapping by joint "
                              "name is for URDF robots)")
        if len(drives) != n:
            raise ConfigError(f"{source}: drives has {len(drives)} entries but dh.rows has {n}")
        return tuple(_drive(e, i, f"{source}: drives[{i}]") for i, e in enumerate(drives))
    if not isinstance(drives, dict):
        raise ConfigError(f"{source}: drives: a URDF robot's drives are a mapping joint name -> drive")
    return tuple(_drive(e, str(k), f"{source}: drives.{k}") for k, e in drives.items())


def parse_robot(doc: object, source: str, base_dir: Path | None = None) -> RobotDescription:
    """Validate a robot document (already parsed YAML) and convert it to SI / radians."""
    if not isinstance(doc, dict):
        raise ConfigError(f"{source}: a robot file must be a mapping of keys, got {type(doc).__name__}")
    doc = validate(doc, "robot", source)  # integral floats as ints where the schema says integer
    if "arms" in doc:
        raise ConfigError(f"{source}: describes a platform of arms ('arms'); this needs a single arm given by "
                          "'dh' or 'urdf'")
    if "captures" in doc:
        raise ConfigError(f"{source}: 'captures' belong to a platform of arms ('arms')")
    has_dh, has_urdf = "dh" in doc, "urdf" in doc
    if has_dh == has_urdf:
        raise ConfigError(f"{source}: give exactly one of 'dh' (with 'links') or 'urdf' (or 'arms' for a platform)")
    tool = doc.get("tool", {})
    common = dict(
        name=doc["name"],
        source=source,
        tool=transform(tool.get("xyz_m", [0, 0, 0]), tool.get("rpy_deg", [0, 0, 0])),
        base_com_m=np.asarray(doc.get("base_com_m", [0, 0, 0]), dtype=float),
        gravity_mps2=np.asarray(doc.get("gravity_mps2", [0, 0, 0]), dtype=float),
    )
    ranges = None
    if "joint_range_deg" in doc:
        ranges = np.deg2rad(np.asarray(doc["joint_range_deg"], dtype=float))
        for i, (lo, hi) in enumerate(ranges):
            if not lo < hi:
                raise ConfigError(f"{source}: joint_range_deg[{i}] = {doc['joint_range_deg'][i]}: lower must be < upper")
    if not has_urdf:
        for key in ("locked", "joints"):
            if key in doc:
                raise ConfigError(f"{source}: '{key}' is only for URDF robots (a DH robot's joints all move)")
    if has_urdf:
        if "links" in doc:
            raise ConfigError(f"{source}: 'links' is only for DH robots; a URDF carries its own inertias")
        if "package" in doc["urdf"]:
            path = package_file(doc["urdf"]["package"], doc["urdf"]["path"], source)
        else:
            path = Path(doc["urdf"]["path"])
            if not path.is_absolute() and base_dir is not None:
                path = base_dir / path
        if not path.is_file():
            raise ConfigError(f"{source}: urdf.path = {doc['urdf']['path']!r}: "
                              f"{'not a regular file' if path.exists() else 'no such file'}")
        check_urdf(path, source)
        joints = tuple(doc["joints"]) if "joints" in doc else None
        return RobotDescription(convention=None, dh=None, links=(), joint_range_rad=ranges,
                                urdf_path=path, urdf_ee_frame=doc["urdf"]["ee_frame"],
                                urdf_locked=tuple((str(k), float(v)) for k, v in doc.get("locked", {}).items()),
                                urdf_joints=joints, drives=_drives(doc, source, None), **common)
    if "links" not in doc:
        raise ConfigError(f"{source}: a DH robot needs 'links' (mass, centre of mass, inertia per link)")
    rows = np.asarray(doc["dh"]["rows"], dtype=float)
    n = len(rows)
    if len(doc["links"]) != n:
        raise ConfigError(f"{source}: links has {len(doc['links'])} entries but dh.rows has {n}")
    if ranges is None:
        raise ConfigError(f"{source}: joint_range_deg is required for a DH robot")
    if len(ranges) != n:
        raise ConfigError(f"{source}: joint_range_deg has {len(ranges)} entries but dh.rows has {n}")
    dh = rows.copy()
    dh[:, 0] = np.deg2rad(rows[:, 0])
    dh[:, 2] = np.deg2rad(rows[:, 2])
    links = tuple(
        LinkInertia(
            mass_kg=float(link["mass_kg"]),
            com_m=np.asarray(link["com_m"], dtype=float),
            inertia_kgm2=_inertia_matrix(link["inertia_kgm2"], f"{source}: links[{i}].inertia_kgm2"),
        )
        for i, link in enumerate(doc["links"])
    )
    return RobotDescription(convention=doc["dh"]["convention"], dh=dh, links=links, joint_range_rad=ranges,
                            drives=_drives(doc, source, n), **common)


def load_robot(path: str | Path) -> RobotDescription:
    """Read and validate a robot YAML file."""
    path = Path(path)
    return parse_robot(load_yaml(path), str(path), base_dir=path.parent)


# --------------------------------------------------------------------------- building


def load(path: str | Path) -> Robot:
    """Read, validate and build a robot file in one step."""
    return build_robot(load_robot(path))


def lock_classes(robot: Robot, angle_deg: float | None = None) -> list[str]:
    """One line per joint locked in turn (at ``angle_deg`` clipped to its range; default mid-range,
    plus "no joint locked" for a 6-joint arm): the remaining chain's axis geometry and IK method
    (:func:`capmap.core.ik.classify`)."""
    lines = [f"no joint locked: {classify(free(robot).chain).describe()}"] if robot.n_joints == 6 else []
    for j in range(1, robot.n_joints + 1):
        lo, hi = robot.q_lower[j - 1], robot.q_upper[j - 1]
        angle = (lo + hi) / 2 if angle_deg is None else float(np.clip(np.deg2rad(angle_deg), lo, hi))
        lines.append(f"joint {j} locked at {np.rad2deg(angle):g} deg: {classify(lock(robot, j, angle).chain).describe()}")
    return lines


def locked_arm(robot: Robot, joint: int, angle_deg: float) -> LockedArm:
    """``robot`` with ``joint`` (1-based) locked at ``angle_deg``: :func:`capmap.core.reduction.lock` with its
    errors in config terms. The capacity map takes every IK branch of a pose: the locked arm must have
    exactly 6 moving joints (a 7-joint arm with one locked); any other count is one line naming the file."""
    if robot.n_joints != 7:
        raise ConfigError(f"{robot.description.source}: {robot.name} has {robot.n_joints} moving joints, so "
                          f"{robot.n_joints - 1} move with one locked; the capacity map needs 6 (every IK branch of a "
                          "pose is finite only then): give a 7-joint arm (a URDF's joints/locked keys choose them)")
    try:
        return lock(robot, joint, np.deg2rad(angle_deg))
    except CapmapError as exc:
        raise ConfigError(exc.in_terms(joint="lock.joint", angle="lock.angle_deg")) from None


def run_arm(run: RunConfig) -> LockedArm:
    """The run's robot locked as its resolved failure says (``arm.robot``: the robot)."""
    return locked_arm(load(run.robot), run.failure.joint, run.failure.angle_deg)
