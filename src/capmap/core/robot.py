"""A robot description (SI, radians) -> Pinocchio model.

A :class:`RobotDescription` holds either DH rows (modified/Craig or standard) with per-link mass,
centre of mass and inertia, or a URDF file's path; :mod:`capmap.robots` parses robot files into it.

The model is built once (:func:`build_robot`) and treated as immutable; each worker makes
its own ``pin.Data``. Frames: ``link<i>`` is DH frame i, ``ee`` is the end effector
(last DH frame composed with the tool transform, or the URDF frame named in the file).

A URDF robot may hold joints fixed (``locked``: joint name -> value, rad or m; the model is
reduced with ``pin.buildReducedModel``, e.g. a gripper's fingers, a head, a torso) and name the
arm's joints (``joints``, root first); what remains must be a serial chain of 1-DOF revolute
joints. Its joints' ``<limit effort>`` are kept (:attr:`Robot.effort_limit_nm`): a run's default torque limits.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from capmap.errors import ConfigError

__all__ = ["EE_FRAME", "Drive", "LinkInertia", "RobotDescription", "Robot", "build_robot"]

EE_FRAME = "ee"


@dataclass(frozen=True)
class LinkInertia:
    """Rigid-body data of one link, in its link frame (SI)."""

    mass_kg: float
    com_m: np.ndarray  # (3,)
    inertia_kgm2: np.ndarray  # (3, 3) about the centre of mass, link-frame axes


@dataclass(frozen=True)
class Drive:
    """One joint's drive as a robot file states it (SI): the joint (0-based index of a DH robot, or a URDF
    joint name), its reflected rotor inertia armature_kgm2 and its friction at the joint, Coulomb
    coulomb_nm and viscous viscous_nms; None: not stated (a URDF's <dynamics>, else 0)."""

    joint: int | str
    armature_kgm2: float | None = None
    coulomb_nm: float | None = None
    viscous_nms: float | None = None


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
    urdf_locked: tuple[tuple[str, float], ...] = ()  # URDF joints held fixed: (name, value rad or m), file order
    urdf_joints: tuple[str, ...] | None = None  # the arm's joints as the file names them (None: every joint not locked)
    drives: tuple[Drive, ...] = ()  # the robot file's drives (rotor inertia, friction), joints not named keep defaults

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
    effort_limit_nm: np.ndarray | None = None  # (n,) the URDF's <limit effort> of each joint (None: a DH robot)

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
    def armature_kgm2(self) -> np.ndarray:
        """(n,) each joint's reflected rotor inertia, kg m^2 (Pinocchio's ``model.armature``: in its RNEA and CRBA)."""
        return np.asarray(self.model.armature, dtype=float).copy()

    @property
    def coulomb_nm(self) -> np.ndarray:
        """(n,) each joint's Coulomb friction torque, N m (``model.friction``; a URDF's <dynamics friction>)."""
        return np.asarray(self.model.friction, dtype=float).copy()

    @property
    def viscous_nms(self) -> np.ndarray:
        """(n,) each joint's viscous friction, N m s/rad (``model.damping``; a URDF's <dynamics damping>)."""
        return np.asarray(self.model.damping, dtype=float).copy()

    @property
    def has_friction(self) -> bool:
        return bool(np.any(self.coulomb_nm > 0) or np.any(self.viscous_nms > 0))

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


_REVOLUTE = frozenset({"JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned"})
_PRISMATIC = frozenset({"JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned"})
_UNBOUNDED = frozenset({"JointModelRUBX", "JointModelRUBY", "JointModelRUBZ", "JointModelRevoluteUnboundedUnaligned"})


def _kind(jmodel) -> str:
    name = jmodel.shortname()
    return ("revolute" if name in _REVOLUTE else "prismatic" if name in _PRISMATIC
            else "continuous" if name in _UNBOUNDED else name.removeprefix("JointModel"))


def _locked_reference(desc: RobotDescription, model: pin.Model) -> tuple[list[int], np.ndarray]:
    """The joints to lock (ids) and the reference configuration holding them at their values; a
    joint the URDF does not have, a value outside its range, a joint that is not 1-DOF: one line
    naming ``locked.<name>``."""
    q_ref = pin.neutral(model)
    ids = []
    for name, value in desc.urdf_locked:
        key = f"{desc.source}: locked.{name}"
        if name == model.names[0] or not model.existJointName(name):  # names[0]: 'universe', no joint
            movable = [model.names[j] for j in range(1, model.njoints)]
            raise ConfigError(f"{key}: the URDF has no movable joint {name!r} (its joints: {', '.join(movable)})")
        j = model.getJointId(name)
        jm, kind = model.joints[j], _kind(model.joints[j])
        if not np.isfinite(value):
            raise ConfigError(f"{key} = {value}: not a finite value")
        if kind == "continuous":  # unbounded: (cos, sin) in the configuration
            q_ref[jm.idx_q:jm.idx_q + 2] = np.cos(value), np.sin(value)
        elif kind in ("revolute", "prismatic"):
            lo, hi = model.lowerPositionLimit[jm.idx_q], model.upperPositionLimit[jm.idx_q]
            if not lo - 1e-12 <= value <= hi + 1e-12:
                unit = "rad" if kind == "revolute" else "m"
                raise ConfigError(f"{key} = {value:g} {unit} is outside the joint's range [{lo:g}, {hi:g}] {unit}")
            q_ref[jm.idx_q] = value
        else:
            raise ConfigError(f"{key}: a {kind} joint ({jm.nv} DOF) cannot be locked at one value")
        ids.append(j)
    return ids, q_ref


def _check_chain(desc: RobotDescription, model: pin.Model) -> None:
    """What remains after locking is a serial chain of 1-DOF revolute joints, in the order of
    ``joints`` when the file names them, ending at ``urdf.ee_frame``; else one line naming the joints."""
    names = list(model.names[1:])
    hint = "hold the others fixed in 'locked' (e.g. a gripper's fingers) or name the arm in 'joints'"
    bad = [f"{n} ({_kind(model.joints[j])})" for j, n in enumerate(names, start=1)
           if _kind(model.joints[j]) != "revolute"]
    if bad:
        raise ConfigError(f"{desc.source}: the arm must be a serial chain of 1-DOF revolute joints, but "
                          f"{', '.join(bad)} {'is' if len(bad) == 1 else 'are'} not: {hint}")
    branches = [f"{names[j - 1]} follows {model.names[model.parents[j]] if model.parents[j] else 'the base'}, "
                f"not {names[j - 2]}" for j in range(2, model.njoints) if model.parents[j] != j - 1]
    if branches:
        raise ConfigError(f"{desc.source}: the joints {', '.join(names)} are not a serial chain ({'; '.join(branches)}): "
                          f"{hint}")
    if desc.urdf_joints is not None and tuple(names) != desc.urdf_joints:
        raise ConfigError(f"{desc.source}: joints = [{', '.join(desc.urdf_joints)}] is not the chain's order root "
                          f"first ({', '.join(names)})")
    frame = model.frames[model.getFrameId(desc.urdf_ee_frame)]
    if names and frame.parentJoint != model.njoints - 1:
        on = model.names[frame.parentJoint] if frame.parentJoint else "the base"
        raise ConfigError(f"{desc.source}: urdf.ee_frame = {desc.urdf_ee_frame!r} is moved by {on}, not by the "
                          f"chain's last joint {names[-1]}")


def _build_urdf_model(desc: RobotDescription) -> tuple[pin.Model, np.ndarray]:
    try:
        full = pin.buildModelFromUrdf(str(desc.urdf_path))
    except Exception as exc:  # Pinocchio raises bare ValueError/RuntimeError from C++
        raise ConfigError(f"{desc.source}: urdf.path = {str(desc.urdf_path)!r}: cannot be parsed "
                          f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    if not full.existFrame(desc.urdf_ee_frame):
        raise ConfigError(f"{desc.source}: urdf.ee_frame = {desc.urdf_ee_frame!r} is not a frame of the URDF")
    locked, q_ref = _locked_reference(desc, full)
    if desc.urdf_joints is not None:
        absent = [n for n in desc.urdf_joints if n == full.names[0] or not full.existJointName(n)]
        if absent:
            raise ConfigError(f"{desc.source}: joints: the URDF has no movable joint {absent[0]!r}")
        both = [n for n in desc.urdf_joints if n in dict(desc.urdf_locked)]
        if both:
            raise ConfigError(f"{desc.source}: joints: {both[0]} is also in locked (a joint moves or is held fixed)")
        neither = [full.names[j] for j in range(1, full.njoints)
                   if full.names[j] not in desc.urdf_joints and j not in locked]
        if neither:
            raise ConfigError(f"{desc.source}: the URDF's joints {', '.join(neither)} are neither in joints nor in "
                              "locked: add each to one of them (locked: a value, rad or m)")
    model = pin.buildReducedModel(full, locked, q_ref) if locked else full
    _check_chain(desc, model)
    src = model.frames[model.getFrameId(desc.urdf_ee_frame)]
    model.addFrame(pin.Frame(EE_FRAME, src.parentJoint, model.getFrameId(desc.urdf_ee_frame),
                             src.placement * _se3(desc.tool), pin.FrameType.OP_FRAME))
    ranges = np.stack([model.lowerPositionLimit, model.upperPositionLimit], axis=1)
    for name, (lo, hi) in zip(model.names[1:], ranges if desc.joint_range_rad is None else ()):
        if not lo < hi:
            raise ConfigError(f"{desc.source}: urdf.path = {str(desc.urdf_path)!r}: joint {name}'s limits are lower "
                              f"{lo:g} rad, upper {hi:g} rad: lower must be < upper (fix the URDF or give joint_range_deg)")
    return model, ranges


def _apply_drives(desc: RobotDescription, model: pin.Model) -> None:
    """Write the description's drives into Pinocchio's own fields (armature, friction: Coulomb, damping:
    viscous), over a URDF's <dynamics> values; a joint the arm does not have is one line naming
    ``drives.<joint>``."""
    names = list(model.names[1:])
    for d in desc.drives:
        if isinstance(d.joint, str):
            if d.joint not in names:
                locked = " (it is locked)" if d.joint in dict(desc.urdf_locked) else ""
                raise ConfigError(f"{desc.source}: drives.{d.joint}: not a joint of the arm{locked} "
                                  f"(its joints: {', '.join(names)})")
            i = names.index(d.joint)
        else:
            i = d.joint
        for field_, value in (("armature", d.armature_kgm2), ("friction", d.coulomb_nm), ("damping", d.viscous_nms)):
            if value is not None:
                getattr(model, field_)[i] = value


def build_robot(desc: RobotDescription) -> Robot:
    """Build the Pinocchio model(s) of a validated description (do this once per process)."""
    effort = None
    if desc.urdf_path is not None:
        model, urdf_ranges = _build_urdf_model(desc)
        effort = np.asarray(model.effortLimit, dtype=float).copy()  # one per joint: 1-DOF joints (checked)
        ranges = desc.joint_range_rad if desc.joint_range_rad is not None else urdf_ranges
        if len(ranges) != model.nq:
            raise ConfigError(f"{desc.source}: joint_range_deg has {len(ranges)} entries but the URDF has "
                              f"{model.nq} joints")
    else:
        model = _build_dh_model(desc)
        ranges = desc.joint_range_rad
    _apply_drives(desc, model)
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
        effort_limit_nm=effort,
    )
