"""Robot description -> Pinocchio model.

A robot is described in YAML (schema ``capmap/schemas/robot.schema.json``), either by
DH rows (modified/Craig or standard) with per-link mass, centre of mass and inertia, or
by a URDF file. Files use degrees; everything past :func:`load_robot` is SI with radians.

The model is built once (:func:`build_robot`) and treated as immutable; each worker makes
its own ``pin.Data``. Frames: ``link<i>`` is DH frame i, ``ee`` is the end effector
(last DH frame composed with the tool transform, or the URDF frame named in the file).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from capmap.errors import CapmapError
from capmap.validation import load_yaml, validate

EE_FRAME = "ee"


@dataclass(frozen=True)
class LinkInertia:
    """Rigid-body data of one link, in its link frame (SI)."""

    mass_kg: float
    com_m: np.ndarray  # (3,)
    inertia_kgm2: np.ndarray  # (3, 3) about the centre of mass, link-frame axes


@dataclass(frozen=True)
class RobotDescription:
    """Validated contents of a robot file (SI units, radians)."""

    name: str
    source: str
    convention: str | None  # "modified" | "standard" | None for URDF
    dh: np.ndarray | None  # (n, 4): alpha_rad, a_m, offset_rad, d_m
    links: tuple[LinkInertia, ...]
    joint_range_rad: np.ndarray | None  # (n, 2); None: take the URDF's limits
    tool: np.ndarray  # (4, 4) homogeneous transform last frame -> end effector
    base_com_m: np.ndarray  # (3,)
    gravity_mps2: np.ndarray  # (3,)
    urdf_path: Path | None = None
    urdf_ee_frame: str | None = None

    @property
    def n_joints(self) -> int:
        return len(self.dh) if self.dh is not None else -1


@dataclass(frozen=True, eq=False)
class Robot:
    """A built robot: Pinocchio models (with and without gravity) plus the task-relevant data.

    ``model`` has the configured gravity, ``model_no_gravity`` is the same arm with zero
    gravity (used for the velocity- and acceleration-dependent parts of the dynamics).
    Joint k (1-based, as users count) is Pinocchio joint id k and configuration index k-1.
    """

    description: RobotDescription
    model: pin.Model
    model_no_gravity: pin.Model
    ee_frame_id: int
    q_lower: np.ndarray  # (n,) rad
    q_upper: np.ndarray  # (n,) rad
    joint_names: tuple[str, ...] = field(default=())

    @property
    def name(self) -> str:
        return self.description.name

    @property
    def n_joints(self) -> int:
        return self.model.nq

    @property
    def gravity(self) -> np.ndarray:
        return self.description.gravity_mps2

    @property
    def base_com(self) -> np.ndarray:
        return self.description.base_com_m

    def fk(self, q: np.ndarray) -> np.ndarray:
        """End-effector pose(s) by Pinocchio. q: (n,) or (N, n) rad -> (4, 4) or (N, 4, 4)."""
        q = np.asarray(q, dtype=float)
        data = self.model.createData()
        out = []
        for qi in np.atleast_2d(q):
            pin.framesForwardKinematics(self.model, data, qi)
            out.append(data.oMf[self.ee_frame_id].homogeneous.copy())
        out = np.array(out)
        return out[0] if q.ndim == 1 else out


# --------------------------------------------------------------------------- parsing


def _inertia_matrix(values: list[float], where: str) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if len(v) == 3:
        inertia = np.diag(v)
    elif len(v) == 6:
        ixx, iyy, izz, ixy, ixz, iyz = v
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    else:
        raise CapmapError(f"{where}: expected 3 (principal) or 6 values, got {len(v)}")
    eig = np.linalg.eigvalsh(inertia)
    if eig.min() <= 0:
        raise CapmapError(f"{where}: inertia is not positive definite (eigenvalues {np.round(eig, 6).tolist()})")
    a, b, c = np.sort(eig)
    if a + b < c * (1 - 1e-9):
        raise CapmapError(f"{where}: principal moments {np.round(eig, 6).tolist()} violate the triangle "
                          "inequality (no rigid body has them)")
    return inertia


def _transform(xyz, rpy_deg) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(*np.deg2rad(rpy_deg))
    T[:3, 3] = xyz
    return T


def package_file(package: str, path: str, source: str) -> Path:
    """A file shipped by an installed pip distribution (e.g. example-robot-data's URDFs), found by
    the end of its installed path, so the distribution's own prefix layout does not matter."""
    from importlib import metadata

    try:
        dist = metadata.distribution(package)
    except metadata.PackageNotFoundError:
        raise CapmapError(f"{source}: urdf.package = {package!r} is not installed (pip install {package})") from None
    want = "/" + path.strip("/")
    hits = [f for f in (dist.files or []) if ("/" + str(f)).endswith(want)]
    if len(hits) != 1:
        raise CapmapError(f"{source}: urdf.path = {path!r}: {len(hits)} files of {package} end with it (need one)")
    return Path(dist.locate_file(hits[0]))


def parse_robot(doc: object, source: str, base_dir: Path | None = None) -> RobotDescription:
    """Validate a robot document (already parsed YAML) and convert it to SI / radians."""
    if not isinstance(doc, dict):
        raise CapmapError(f"{source}: a robot file must be a mapping of keys, got {type(doc).__name__}")
    validate(doc, "robot", source)
    has_dh, has_urdf = "dh" in doc, "urdf" in doc
    if has_dh == has_urdf:
        raise CapmapError(f"{source}: give exactly one of 'dh' (with 'links') or 'urdf'")
    tool = doc.get("tool", {})
    common = dict(
        name=doc["name"],
        source=source,
        tool=_transform(tool.get("xyz_m", [0, 0, 0]), tool.get("rpy_deg", [0, 0, 0])),
        base_com_m=np.asarray(doc.get("base_com_m", [0, 0, 0]), dtype=float),
        gravity_mps2=np.asarray(doc.get("gravity_mps2", [0, 0, 0]), dtype=float),
    )
    ranges = None
    if "joint_range_deg" in doc:
        ranges = np.deg2rad(np.asarray(doc["joint_range_deg"], dtype=float))
        for i, (lo, hi) in enumerate(ranges):
            if not lo < hi:
                raise CapmapError(f"{source}: joint_range_deg[{i}] = {doc['joint_range_deg'][i]}: lower must be < upper")
    if has_urdf:
        if "links" in doc:
            raise CapmapError(f"{source}: 'links' is only for DH robots; a URDF carries its own inertias")
        if "package" in doc["urdf"]:
            path = package_file(doc["urdf"]["package"], doc["urdf"]["path"], source)
        else:
            path = Path(doc["urdf"]["path"])
            if not path.is_absolute() and base_dir is not None:
                path = base_dir / path
        if not path.is_file():
            raise CapmapError(f"{source}: urdf.path = {doc['urdf']['path']!r}: no such file")
        return RobotDescription(convention=None, dh=None, links=(), joint_range_rad=ranges,
                                urdf_path=path, urdf_ee_frame=doc["urdf"]["ee_frame"], **common)
    if "links" not in doc:
        raise CapmapError(f"{source}: a DH robot needs 'links' (mass, centre of mass, inertia per link)")
    rows = np.asarray(doc["dh"]["rows"], dtype=float)
    n = len(rows)
    if len(doc["links"]) != n:
        raise CapmapError(f"{source}: links has {len(doc['links'])} entries but dh.rows has {n}")
    if ranges is None:
        raise CapmapError(f"{source}: joint_range_deg is required for a DH robot")
    if len(ranges) != n:
        raise CapmapError(f"{source}: joint_range_deg has {len(ranges)} entries but dh.rows has {n}")
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
    return RobotDescription(convention=doc["dh"]["convention"], dh=dh, links=links, joint_range_rad=ranges, **common)


def load_robot(path: str | Path) -> RobotDescription:
    """Read and validate a robot YAML file."""
    path = Path(path)
    return parse_robot(load_yaml(path), str(path), base_dir=path.parent)


# --------------------------------------------------------------------------- building


def _se3(T: np.ndarray) -> pin.SE3:
    return pin.SE3(T[:3, :3].copy(), T[:3, 3].copy())


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    T = np.eye(4)
    T[1:3, 1:3] = [[c, -s], [s, c]]
    return T


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def _tx(a):
    T = np.eye(4)
    T[0, 3] = a
    return T


def _tz(d):
    T = np.eye(4)
    T[2, 3] = d
    return T


def dh_transform(convention: str, alpha: float, a: float, theta: float, d: float) -> np.ndarray:
    """One DH step T(i-1, i) (4x4). For ``modified`` alpha, a are alpha_{i-1}, a_{i-1}."""
    if convention == "modified":
        return _rx(alpha) @ _tx(a) @ _rz(theta) @ _tz(d)
    return _rz(theta) @ _tz(d) @ _tx(a) @ _rx(alpha)


def _build_dh_model(desc: RobotDescription) -> pin.Model:
    """Pinocchio model of a DH arm: joint i rotates about z of its joint frame.

    Modified DH: joint frame i = DH frame i. Placement of joint i in joint i-1 is
    Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(offset_i) Tz(d_i) (Rz(q) commutes with Tz(d)).
    Standard DH: joint frame i = DH frame i-1 rotated by offset_i + q_i about its z;
    DH frame i = joint frame i * Tz(d_i) Tx(a_i) Rx(alpha_i), where link i's inertia lives.
    """
    model = pin.Model()
    model.name = desc.name
    parent, parent_frame = 0, 0
    prev_tail = np.eye(4)  # standard DH: joint frame i-1 -> DH frame i-1
    for i, ((alpha, a, offset, d), link) in enumerate(zip(desc.dh, desc.links), start=1):
        if desc.convention == "modified":
            placement, body = _rx(alpha) @ _tx(a) @ _rz(offset) @ _tz(d), np.eye(4)
        else:
            placement, body = prev_tail @ _rz(offset), _tz(d) @ _tx(a) @ _rx(alpha)
            prev_tail = body
        lo, hi = desc.joint_range_rad[i - 1]
        jid = model.addJoint(parent, pin.JointModelRZ(), _se3(placement), f"joint{i}",
                             np.array([1e9]), np.array([1e9]), np.array([lo]), np.array([hi]))
        inertia = pin.Inertia(link.mass_kg, link.com_m, link.inertia_kgm2)
        model.appendBodyToJoint(jid, inertia, _se3(body))
        jframe = model.addJointFrame(jid, parent_frame)
        parent_frame = model.addBodyFrame(f"link{i}", jid, _se3(body), jframe)
        parent = jid
    tail = (prev_tail if desc.convention == "standard" else np.eye(4)) @ desc.tool
    model.addFrame(pin.Frame(EE_FRAME, parent, parent_frame, _se3(tail), pin.FrameType.OP_FRAME))
    return model


def _build_urdf_model(desc: RobotDescription) -> tuple[pin.Model, np.ndarray]:
    try:
        model = pin.buildModelFromUrdf(str(desc.urdf_path))
    except Exception as exc:  # Pinocchio raises bare ValueError/RuntimeError from C++
        raise CapmapError(f"{desc.source}: urdf.path = {str(desc.urdf_path)!r}: cannot be parsed "
                          f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    if not model.existFrame(desc.urdf_ee_frame):
        raise CapmapError(f"{desc.source}: urdf.ee_frame = {desc.urdf_ee_frame!r} is not a frame of the URDF")
    if model.nq != model.nv or any(model.joints[j].nq != 1 for j in range(1, model.njoints)):
        raise CapmapError(f"{desc.source}: only serial arms of 1-DOF revolute joints are supported")
    src = model.frames[model.getFrameId(desc.urdf_ee_frame)]
    model.addFrame(pin.Frame(EE_FRAME, src.parentJoint, model.getFrameId(desc.urdf_ee_frame),
                             src.placement * _se3(desc.tool), pin.FrameType.OP_FRAME))
    ranges = np.stack([model.lowerPositionLimit, model.upperPositionLimit], axis=1)
    return model, ranges


def build_robot(desc: RobotDescription) -> Robot:
    """Build the Pinocchio model(s) of a validated description (do this once per process)."""
    if desc.urdf_path is not None:
        model, urdf_ranges = _build_urdf_model(desc)
        ranges = desc.joint_range_rad if desc.joint_range_rad is not None else urdf_ranges
        if len(ranges) != model.nq:
            raise CapmapError(f"{desc.source}: joint_range_deg has {len(ranges)} entries but the URDF has "
                              f"{model.nq} joints")
    else:
        model = _build_dh_model(desc)
        ranges = desc.joint_range_rad
    model.gravity = pin.Motion(np.asarray(desc.gravity_mps2, dtype=float), np.zeros(3))
    model_ng = model.copy()
    model_ng.gravity = pin.Motion.Zero()
    return Robot(
        description=desc,
        model=model,
        model_no_gravity=model_ng,
        ee_frame_id=model.getFrameId(EE_FRAME),
        q_lower=np.asarray(ranges[:, 0], dtype=float),
        q_upper=np.asarray(ranges[:, 1], dtype=float),
        joint_names=tuple(model.names[1:]),
    )


def load(path: str | Path) -> Robot:
    """Read, validate and build a robot file in one step."""
    return build_robot(load_robot(path))
