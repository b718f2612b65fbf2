"""A fixed-base robot with two arms (Baxter): its reduced Pinocchio model (head and fingers locked)
and its capsules, fitted to the URDF's collision geometry.

Configuration q (14,) = left arm joints then right arm joints (as listed in the robot file);
velocities likewise. A capsule is given in its parent joint's frame (the universe for the
static body: torso, head, pedestal).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from capmap.dualarm.primitives import Capsule, box_points, cylinder_points, fit_capsule
from capmap.errors import CapmapError

__all__ = ["CapsuleGroup", "DualArmDescription", "DualArm", "LinkCapsule", "build_dual_arm", "fit_capsules",
           "geometry_balls"]


@dataclass(frozen=True)
class CapsuleGroup:
    """A capsule to fit: its name, the URDF collision objects it covers, and 'left' | 'right' | 'body'."""

    name: str
    geometry: tuple[str, ...]
    part: str


@dataclass(frozen=True)
class DualArmDescription:
    """urdf path; package_dir (the folder the URDF's package:// paths resolve in); the arms' joints
    {'left': (7 names), 'right': ...}, their gripper frames; locked joints and their values; the
    capsule groups (arm groups root first); self_gap: capsules of one arm this many places apart or
    more are checked against each other; body_skip: arm capsules not checked against the body;
    hold: the last capsules of each arm that hold the panel."""

    name: str
    urdf: Path
    package_dir: Path
    arm_joints: dict[str, tuple[str, ...]]
    grippers: dict[str, str]
    locked: dict[str, float]
    groups: tuple[CapsuleGroup, ...]
    body_skip: int
    hold: int
    self_gap: int = 2


@dataclass(frozen=True)
class LinkCapsule:
    """A fitted capsule: name, part ('left' | 'right' | 'body'), its index along its arm, the joint
    it rides on (name), the segment a, b (3,) m in that joint's frame and radius r m."""

    name: str
    part: str
    order: int
    joint: str
    a: np.ndarray
    b: np.ndarray
    r: float


@dataclass(frozen=True, eq=False)
class DualArm:
    """The reduced model (nq = 14), its geometry model, gripper frame ids, limits and capsules."""

    description: DualArmDescription
    model: pin.Model
    geometry: pin.GeometryModel
    gripper_frames: dict[str, int]
    q_lower: np.ndarray
    q_upper: np.ndarray
    v_max: np.ndarray
    capsules: tuple[LinkCapsule, ...] = ()

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.model.names[1:])


def build_dual_arm(desc: DualArmDescription) -> DualArm:
    """The reduced model and geometry (no capsules yet: see :func:`fit_capsules`)."""
    try:
        model = pin.buildModelFromUrdf(str(desc.urdf))
        geom = pin.buildGeomFromUrdf(model, str(desc.urdf), pin.GeometryType.COLLISION, package_dirs=[str(desc.package_dir)])
    except Exception as exc:  # Pinocchio raises bare errors from C++
        raise CapmapError(f"{{urdf}} {desc.urdf}: cannot be loaded ({str(exc).splitlines()[0] if str(exc) else exc})",
                          urdf="URDF") from None
    for name in (*desc.locked, *desc.arm_joints["left"], *desc.arm_joints["right"]):
        if not model.existJointName(name):
            raise CapmapError(f"{{urdf}} has no joint {name!r}", urdf=f"URDF {desc.urdf.name}")
    moving = list(desc.arm_joints["left"]) + list(desc.arm_joints["right"])
    q_ref = pin.neutral(model)
    lock = []
    for j in range(1, model.njoints):
        name = model.names[j]
        if name in moving:
            continue
        if model.joints[j].nq != 1:
            raise CapmapError(f"joint {name} is not 1-DOF; it cannot be locked")
        q_ref[model.joints[j].idx_q] = desc.locked.get(name, 0.0)
        lock.append(j)
    reduced, (geom_r,) = pin.buildReducedModel(model, [geom], lock, q_ref)
    if list(reduced.names[1:]) != moving:
        raise CapmapError(f"the arms' joints {moving} are not the robot's remaining joints in that order "
                          f"({list(reduced.names[1:])})")
    grippers = {}
    for side, frame in desc.grippers.items():
        if not reduced.existFrame(frame):
            raise CapmapError(f"{{urdf}} has no frame {frame!r} for the {side} gripper", urdf=f"URDF {desc.urdf.name}")
        grippers[side] = reduced.getFrameId(frame)
    return DualArm(desc, reduced, geom_r, grippers, reduced.lowerPositionLimit.copy(), reduced.upperPositionLimit.copy(),
                   reduced.velocityLimit.copy())


def geometry_balls(obj: pin.GeometryObject) -> tuple[np.ndarray, np.ndarray]:
    """Balls (centres (n, 3) m in the parent joint's frame, radii (n,)) whose hull contains a collision
    object: cylinder rims (circumscribed), box corners, the sphere itself, mesh vertices."""
    g = obj.geometry
    if isinstance(g, coal.Cylinder):
        local, radii = cylinder_points(g.radius, g.halfLength), None
    elif isinstance(g, coal.Box):
        local, radii = box_points(g.halfSide), None
    elif isinstance(g, coal.Sphere):
        local, radii = np.zeros((1, 3)), np.array([g.radius])
    elif isinstance(g, coal.Capsule):
        local = np.array([[0, 0, -g.halfLength], [0, 0, g.halfLength]])
        radii = np.full(2, g.radius)
    elif isinstance(g, coal.BVHModelBase):
        local, radii = np.asarray(g.vertices(), dtype=float), None
    else:
        raise CapmapError(f"collision object {obj.name}: unsupported geometry {type(g).__name__}")
    centres = local @ obj.placement.rotation.T + obj.placement.translation
    return centres, np.zeros(len(centres)) if radii is None else radii


def fit_capsules(robot: DualArm) -> tuple[DualArm, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """The robot with a minimum-volume capsule per group, and the balls each was fitted to."""
    gm = robot.geometry
    objects = {o.name: o for o in gm.geometryObjects}
    out, balls = [], {}
    order = {"left": 0, "right": 0, "body": 0}
    for grp in robot.description.groups:
        missing = [n for n in grp.geometry if n not in objects]
        if missing:
            raise CapmapError(f"capsule {grp.name}: {{urdf}} has no collision object {missing[0]!r}",
                              urdf=f"URDF {robot.description.urdf.name}")
        joints = {objects[n].parentJoint for n in grp.geometry}
        if len(joints) != 1:
            raise CapmapError(f"capsule {grp.name}: its collision objects ride on different joints "
                              f"({', '.join(robot.model.names[j] for j in sorted(joints))})")
        c, r = (np.concatenate(x) for x in zip(*(geometry_balls(objects[n]) for n in grp.geometry)))
        cap: Capsule = fit_capsule(c, r)
        joint = robot.model.names[joints.pop()]
        out.append(LinkCapsule(grp.name, grp.part, order[grp.part], joint, cap.a, cap.b, cap.r))
        order[grp.part] += 1
        balls[grp.name] = (c, r)
    return DualArm(robot.description, robot.model, robot.geometry, robot.gripper_frames, robot.q_lower, robot.q_upper,
                   robot.v_max, tuple(out)), balls
