"""A platform carrying several arms of revolute and passive cylindrical joints (SI, radians).

Each arm is a chain of joint frames: joint k's frame is its placement in the previous joint's
frame *after* that joint moved (the first joint's in the arm's mount frame); a revolute
joint turns by q about its axis, a cylindrical joint moves by Tz(d) Rz(theta) along and
about its axis (axes as unit vectors in the joint frame; z when aligned). Links are named
``<arm>.<joint>`` (the body that joint moves), ``<arm>.ee`` (the last joint's frame and the
tool transform) and ``<arm>.mount``. A capture holds two links together:
T(link_a) = T(link_b) @ transform.

A :class:`PlatformState` gives every joint its value: revolute angles, and (theta, d) of the
cylindrical joints (locked or not). :func:`platform_model` builds the whole robot in
Pinocchio (cylindrical joints as composites of a prismatic and a revolute joint about the
same axis), the independent reference the closed-chain code is checked against.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from capmap.core.kinematics import FLIP_Z, Chain, align_z
from capmap.errors import CapmapError

__all__ = ["PlatformJoint", "PlatformArm", "Capture", "PlatformDescription", "PlatformState", "joint_motion",
           "arm_elements", "chain_of", "platform_model", "PlatformModel", "link_segments"]


@dataclass(frozen=True)
class PlatformJoint:
    """name: qualified ``<arm>.<joint>``; kind: 'revolute' | 'cylindrical'; placement (4, 4) in the
    previous joint frame; axis (3,) unit; range_rad (2,) of q or theta; range_m (2,) of d
    (cylindrical only)."""

    name: str
    kind: str
    placement: np.ndarray
    axis: np.ndarray
    range_rad: np.ndarray
    range_m: np.ndarray | None = None

    @property
    def passive(self) -> bool:
        return self.kind == "cylindrical"


@dataclass(frozen=True)
class PlatformArm:
    """An arm: its name, mount (4, 4) on the platform, joints (root first) and tool (4, 4)."""

    name: str
    mount: np.ndarray
    joints: tuple[PlatformJoint, ...]
    tool: np.ndarray

    @property
    def links(self) -> tuple[str, ...]:
        return (f"{self.name}.mount", *(j.name for j in self.joints), f"{self.name}.ee")

    @property
    def revolute(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints if not j.passive)


@dataclass(frozen=True)
class Capture:
    """Two links held together: T(link_a) = T(link_b) @ transform (4, 4)."""

    name: str
    link_a: str
    link_b: str
    transform: np.ndarray


@dataclass(frozen=True)
class PlatformDescription:
    """A validated platform robot: name, source file, arms and capture interfaces."""

    name: str
    source: str
    arms: tuple[PlatformArm, ...]
    captures: tuple[Capture, ...] = ()

    def arm(self, name: str) -> PlatformArm:
        for a in self.arms:
            if a.name == name:
                return a
        raise CapmapError(f"{self.name} has no arm {name!r} (arms: {', '.join(a.name for a in self.arms)})")

    def arm_of(self, link: str) -> PlatformArm:
        """The arm a link (or joint) belongs to."""
        return self.arm(link.split(".", 1)[0])

    def joint(self, name: str) -> PlatformJoint:
        for j in self.arm_of(name).joints:
            if j.name == name:
                return j
        raise CapmapError(f"{self.name} has no joint {name!r}")

    def capture(self, name: str) -> Capture:
        for c in self.captures:
            if c.name == name:
                return c
        raise CapmapError(f"{self.name} has no capture {name!r} (captures: "
                          f"{', '.join(c.name for c in self.captures) or 'none'})")

    @property
    def links(self) -> tuple[str, ...]:
        return tuple(link for a in self.arms for link in a.links)


@dataclass(frozen=True)
class PlatformState:
    """Joint values: q (name -> rad) for revolute joints, passive (name -> (theta rad, d m)) for
    cylindrical joints (absent: locked at 0)."""

    q: dict[str, float]
    passive: dict[str, tuple[float, float]] = field(default_factory=dict)

    def with_values(self, names: tuple[str, ...], values: np.ndarray) -> "PlatformState":
        return PlatformState({**self.q, **dict(zip(names, map(float, values)))}, dict(self.passive))

    def with_passive(self, name: str, theta: float, d: float) -> "PlatformState":
        return PlatformState(dict(self.q), {**self.passive, name: (float(theta), float(d))})


def joint_motion(theta: float, d: float) -> np.ndarray:
    """Tz(d) Rz(theta) (4, 4): a cylindrical joint's motion in its aligned frame (z = axis)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, d], [0, 0, 0, 1.0]])


def _align(axis: np.ndarray) -> np.ndarray:
    A = np.eye(4)
    A[:3, :3] = align_z(axis)
    return A


def arm_elements(arm: PlatformArm, link: str, state: PlatformState, unlocked: str | None = None) -> list[tuple]:
    """The arm from the platform to ``link`` as a product of elements: ('fixed', T (4, 4)) or
    ('joint', name, sign) for Rz(sign q) of a revolute joint in its aligned frame, or
    ('unlocked', name, sign) for the cylindrical joint left free. Locked cylindrical joints
    are fixed at their state values."""
    out: list[tuple] = [("fixed", arm.mount)]
    if link == f"{arm.name}.mount":
        return out
    for j in arm.joints:
        A = _align(j.axis)
        A_inv = np.linalg.inv(A)
        if j.name == unlocked:
            out += [("fixed", j.placement @ A), ("unlocked", j.name, 1), ("fixed", A_inv)]
        elif j.passive:
            theta, d = state.passive.get(j.name, (0.0, 0.0))
            out.append(("fixed", j.placement @ A @ joint_motion(theta, d) @ A_inv))
        else:
            out += [("fixed", j.placement @ A), ("joint", j.name, 1), ("fixed", A_inv)]
        if j.name == link:
            return out
    if link != f"{arm.name}.ee":
        raise CapmapError(f"{link!r} is not a link of arm {arm.name} (links: {', '.join(arm.links)})")
    return out + [("fixed", arm.tool)]


@dataclass(frozen=True, eq=False)
class PlatformModel:
    """The whole robot in Pinocchio: model, the frame id of every link, and the index in q of
    every joint (revolute: its angle; cylindrical: (d, theta))."""

    model: pin.Model
    frames: dict[str, int]
    q_index: dict[str, int]
    data: pin.Data = field(init=False, repr=False)  # the model's one Data (its work arrays)

    def __post_init__(self):
        object.__setattr__(self, "data", self.model.createData())

    def configuration(self, state: PlatformState) -> np.ndarray:
        q = pin.neutral(self.model)
        for name, i in self.q_index.items():
            if name in state.passive:
                q[i], q[i + 1] = state.passive[name][1], state.passive[name][0]
            elif name in state.q:
                q[i] = state.q[name]
        return q

    def placements(self, state: PlatformState, links: tuple[str, ...]) -> np.ndarray:
        """Poses (len(links), 4, 4) of the named links in the platform frame."""
        model, data = self.model, self.data
        pin.forwardKinematics(model, data, self.configuration(state))
        return np.array([pin.updateFramePlacement(model, data, self.frames[name]).homogeneous for name in links])


def platform_model(desc: PlatformDescription) -> PlatformModel:
    """Pinocchio model of every arm on a fixed platform (kinematics only: unit-free massless bodies)."""
    model = pin.Model()
    model.name = desc.name
    frames, q_index = {}, {}
    for arm in desc.arms:
        parent, placement = 0, pin.SE3(arm.mount)
        frames[f"{arm.name}.mount"] = model.addFrame(pin.Frame(f"{arm.name}.mount", 0, 0, placement,
                                                               pin.FrameType.OP_FRAME))
        for j in arm.joints:
            M = placement * pin.SE3(j.placement)
            if j.passive:
                jm = pin.JointModelComposite(pin.JointModelPrismaticUnaligned(j.axis))
                jm.addJoint(pin.JointModelRevoluteUnaligned(j.axis))
            else:
                jm = pin.JointModelRevoluteUnaligned(j.axis)
            jid = model.addJoint(parent, jm, M, j.name)
            q_index[j.name] = model.joints[jid].idx_q
            model.appendBodyToJoint(jid, pin.Inertia.Zero(), pin.SE3.Identity())
            frames[j.name] = model.addFrame(pin.Frame(j.name, jid, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
            parent, placement = jid, pin.SE3.Identity()
        frames[f"{arm.name}.ee"] = model.addFrame(pin.Frame(f"{arm.name}.ee", parent, 0, placement * pin.SE3(arm.tool),
                                                            pin.FrameType.OP_FRAME))
    return PlatformModel(model, frames, q_index)


def chain_of(elements: list[tuple]) -> tuple[Chain, tuple[str, ...]]:
    """A :class:`Chain` (and its joint names) from elements without 'unlocked' ones."""
    X, names, current = [], [], np.eye(4)
    for e in elements:
        if e[0] == "fixed":
            current = current @ e[1]
        elif e[0] == "joint":
            if e[2] > 0:
                X.append(current)
                current = np.eye(4)
            else:  # Rz(-q) = F Rz(q) F with F = Rx(pi)
                X.append(current @ FLIP_Z)
                current = FLIP_Z.copy()
            names.append(e[1])
        else:
            raise CapmapError(f"the unlocked joint {e[1]} cannot be inside a side chain")
    X.append(current)
    return Chain(np.array(X)), tuple(names)



def link_segments(desc: PlatformDescription) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """A stick figure of the robot: (link, start (3,), end (3,)) in the link's own frame, from the
    link's origin to where the next joint (or the tool) sits on it; the body of a cylindrical
    joint also reaches back along its axis by the largest extension (a telescoping boom that
    slides out of its parent); a zero-length piece is left out."""
    out = []
    for arm in desc.arms:
        links = arm.links[:-1]  # mount, then each joint's body; the ee frame carries nothing
        joints = (None, *arm.joints)
        nexts = [j.placement for j in arm.joints] + [arm.tool]
        for link, joint, nxt in zip(links, joints, nexts):
            start = -max(joint.range_m[1], 0.0) * joint.axis if joint is not None and joint.passive else np.zeros(3)
            end = nxt[:3, 3]
            if np.linalg.norm(end - start) > 1e-9:
                out.append((link, start, end.copy()))
    return out
