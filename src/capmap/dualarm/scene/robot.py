"""A fixed-base robot with two arms (Baxter): its reduced Pinocchio model (head and fingers locked)
and its capsules, fitted to the robot's outer shape.

Configuration q (14,) = left arm joints then right arm joints (as listed in the robot file);
velocities likewise. A capsule is given in its parent joint's frame (the universe for the
static body: torso, head, pedestal).

What a capsule covers (``cover`` in the robot file, default both): the URDF objects its group names
in the visual model (the meshes that show the robot's shell) and in the collision model. Every object
of those models that no group names (Baxter's hand camera, range finder and accelerometer, the head's
display, the sonar ring) joins the group on its own joint whose capsule it sticks out of least, so no
part of the robot is left out; an object on a joint without any group is an error.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from capmap.dualarm.geometry.primitives import Capsule, box_points, cylinder_points, fit_capsule
from capmap.errors import CapmapError

__all__ = ["CapsuleGroup", "Covered", "DualArmDescription", "DualArm", "LinkCapsule", "build_dual_arm", "close_fingers",
           "fit_capsules", "geometry_balls"]


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
    hold: the last capsules of each arm that hold the panel; cover: the URDF models the capsules
    cover; fingers: per side the prismatic finger joints and their pad objects, closed on the held
    part's thickness (:func:`close_fingers`)."""

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
    cover: tuple[str, ...] = ("visual", "collision")
    fingers: dict[str, tuple[tuple[str, str], ...]] = field(default_factory=dict)  # side -> ((joint, pad object), ..)


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
    """The reduced model (nq = 14), its collision geometry, gripper frame ids, limits, capsules and
    its visual geometry (None when the URDF has none)."""

    description: DualArmDescription
    model: pin.Model
    geometry: pin.GeometryModel
    gripper_frames: dict[str, int]
    q_lower: np.ndarray
    q_upper: np.ndarray
    v_max: np.ndarray
    capsules: tuple[LinkCapsule, ...] = ()
    visual: pin.GeometryModel | None = None

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.model.names[1:])


def _lowest(obj: pin.GeometryObject, e: np.ndarray) -> float:
    """min over the object of e . x, x in its parent joint's frame (the support function at -e, exact for
    meshes, boxes, cylinders, capsules and spheres)."""
    g, M = obj.geometry, obj.placement
    el = M.rotation.T @ e  # the direction in the object's own frame
    base = float(e @ M.translation)
    if isinstance(g, coal.Cylinder):
        return base - g.halfLength * abs(el[2]) - g.radius * float(np.hypot(el[0], el[1]))
    if isinstance(g, coal.Capsule):
        return base - g.halfLength * abs(el[2]) - g.radius * float(np.linalg.norm(el))
    if isinstance(g, coal.Sphere):
        return base - g.radius * float(np.linalg.norm(el))
    c, r = geometry_balls(obj)  # vertices or corners: exact
    return float((c @ e - r * np.linalg.norm(e)).min())


def close_fingers(desc: DualArmDescription, model: pin.Model, geoms: list[pin.GeometryModel],
                  thickness_m: float) -> dict[str, float]:
    """Finger joint values that close each gripper's pads on a part ``thickness_m`` thick centred
    between them: per finger, its pad's innermost point (over every model's pad object of that name)
    lies thickness / 2 from the gripper frame's origin along the finger joint's axis. A value outside the
    joint's limits (the gripper cannot close that far, or open that wide) is a :class:`CapmapError`."""
    data = model.createData()
    q = pin.neutral(model)
    for name, value in desc.locked.items():
        q[model.joints[model.getJointId(name)].idx_q] = value
    out = {}
    for side, fingers in desc.fingers.items():
        for joint, pad in fingers:
            jid = model.getJointId(joint)
            q[model.joints[jid].idx_q] = 0.0
        pin.framesForwardKinematics(model, data, q)
        grip = data.oMf[model.getFrameId(desc.grippers[side])]
        for joint, pad in fingers:
            jid = model.getJointId(joint)
            jm = model.joints[jid]
            if jm.nq != 1 or not jm.shortname().startswith("JointModelP"):
                raise CapmapError(f"fingers of the {side} arm: {joint} is not a prismatic joint")
            axis_local = _axis_of(jm)
            axis = grip.rotation.T @ (data.oMi[jid].rotation @ axis_local)  # the finger's travel, gripper frame
            objs = [o for gm in geoms for o in gm.geometryObjects if o.name == pad]
            if not objs or any(o.parentJoint != jid for o in objs):
                raise CapmapError(f"fingers of the {side} arm: pad {pad!r} is not a geometry object on joint {joint}")
            # along the travel axis, in the gripper's frame: x_g . axis = (R_gj x_j + p_gj) . axis
            gMj = grip.actInv(data.oMi[jid])
            e_j = gMj.rotation.T @ axis  # the axis in the finger joint's frame
            offset = float(gMj.translation @ axis)
            centre = float(np.mean([o.placement.translation @ e_j for o in objs])) + offset
            sign = 1.0 if centre > 0 else -1.0  # which side of the gripper the finger is on
            inner = min(_lowest(o, sign * e_j) for o in objs) + sign * offset  # its face toward the other finger
            value = sign * (0.5 * thickness_m - inner)
            lo, hi = model.lowerPositionLimit[jm.idx_q], model.upperPositionLimit[jm.idx_q]
            if not lo - 1e-12 <= value <= hi + 1e-12:
                raise CapmapError(f"the {side} gripper cannot close on a part {1e3 * thickness_m:g} mm thick: {joint} "
                                  f"would be at {1e3 * value:.2f} mm, outside its limits [{1e3 * lo:.2f}, {1e3 * hi:.2f}] mm")
            out[joint] = float(np.clip(value, lo, hi))
    return out


def _axis_of(jm) -> np.ndarray:
    fixed = {"X": [1.0, 0, 0], "Y": [0, 1.0, 0], "Z": [0, 0, 1.0]}
    name = jm.shortname()
    if name[-1] in fixed and "Unaligned" not in name:
        return np.array(fixed[name[-1]])
    return np.asarray(jm.extract().axis, dtype=float)


def build_dual_arm(desc: DualArmDescription, hold_thickness_m: float | None = None, visual: bool = True) -> DualArm:
    """The reduced model and geometry (no capsules yet: see :func:`fit_capsules`); with
    ``hold_thickness_m``, the fingers of ``desc.fingers`` closed on a part that thick; ``visual=False``:
    the visual meshes are not loaded (a robot whose capsules and finger values are known already)."""
    try:
        model = pin.buildModelFromUrdf(str(desc.urdf))
        geom = pin.buildGeomFromUrdf(model, str(desc.urdf), pin.GeometryType.COLLISION, package_dirs=[str(desc.package_dir)])
        vis = (pin.buildGeomFromUrdf(model, str(desc.urdf), pin.GeometryType.VISUAL, package_dirs=[str(desc.package_dir)])
               if visual else pin.GeometryModel())
    except Exception as exc:  # Pinocchio raises bare errors from C++
        raise CapmapError(f"{{urdf}} {desc.urdf}: cannot be loaded ({str(exc).splitlines()[0] if str(exc) else exc})",
                          urdf="URDF") from None
    for name in (*desc.locked, *desc.arm_joints["left"], *desc.arm_joints["right"]):
        if not model.existJointName(name):
            raise CapmapError(f"{{urdf}} has no joint {name!r}", urdf=f"URDF {desc.urdf.name}")
    for side, fingers in desc.fingers.items():
        for joint, _ in fingers:
            if not model.existJointName(joint):
                raise CapmapError(f"{{urdf}} has no finger joint {joint!r}", urdf=f"URDF {desc.urdf.name}")
    if hold_thickness_m is not None and desc.fingers:
        desc = replace(desc, locked={**desc.locked, **close_fingers(desc, model, [geom, vis], hold_thickness_m)})
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
    reduced, (geom_r, vis_r) = pin.buildReducedModel(model, [geom, vis], lock, q_ref)
    if list(reduced.names[1:]) != moving:
        raise CapmapError(f"the arms' joints {moving} are not the robot's remaining joints in that order "
                          f"({list(reduced.names[1:])})")
    grippers = {}
    for side, frame in desc.grippers.items():
        if not reduced.existFrame(frame):
            raise CapmapError(f"{{urdf}} has no frame {frame!r} for the {side} gripper", urdf=f"URDF {desc.urdf.name}")
        grippers[side] = reduced.getFrameId(frame)
    return DualArm(desc, reduced, geom_r, grippers, reduced.lowerPositionLimit.copy(), reduced.upperPositionLimit.copy(),
                   reduced.velocityLimit.copy(), visual=vis_r if vis_r.ngeoms else None)


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


@dataclass(frozen=True)
class Covered:
    """What one capsule was fitted to: ball centres (B, 3) m in its joint's frame and radii (B,) m,
    the model each ball came from ('visual' | 'collision', (B,)) and the objects it covers
    ('visual:name' / 'collision:name'), the ones no group named marked with a trailing '*'."""

    centres: np.ndarray
    radii: np.ndarray
    source: np.ndarray
    objects: tuple[str, ...]


def _models(robot: DualArm) -> dict[str, pin.GeometryModel]:
    out = {"collision": robot.geometry}
    if robot.visual is not None:
        out["visual"] = robot.visual
    return out


def _balls(objs: list[tuple[str, pin.GeometryObject]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    parts = [(*geometry_balls(o), kind) for kind, o in objs]
    if not parts:
        return np.zeros((0, 3)), np.zeros(0), np.zeros(0, dtype=object)
    return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]),
            np.concatenate([np.full(len(p[0]), p[2], dtype=object) for p in parts]))


def _excess(cap: Capsule, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """How far each ball (B,) sticks out of a capsule, m (<= 0: inside)."""
    d = cap.b - cap.a
    t = np.clip((centres - cap.a) @ d / max(float(d @ d), 1e-300), 0, 1)
    return np.linalg.norm(centres - cap.a - np.outer(t, d), axis=1) + radii - cap.r


def fit_capsules(robot: DualArm) -> tuple[DualArm, dict[str, Covered]]:
    """The robot with a minimum-volume capsule per group over the geometry of ``description.cover``
    (see the module docstring), and what each capsule covers; every object of the robot's models
    (the covered ones and the others, for the report) is assigned to a capsule on its joint."""
    desc = robot.description
    models = _models(robot)
    names = {kind: {o.name: o for o in gm.geometryObjects} for kind, gm in models.items()}
    claimed = {kind: set() for kind in models}
    members: dict[str, list[tuple[str, pin.GeometryObject, bool]]] = {}
    joint_of: dict[str, int] = {}
    for grp in desc.groups:
        missing = [n for n in grp.geometry if all(n not in v for v in names.values())]
        if missing:
            raise CapmapError(f"capsule {grp.name}: {{urdf}} has no geometry object {missing[0]!r}",
                              urdf=f"URDF {desc.urdf.name}")
        objs = [(kind, names[kind][n], True) for kind in models for n in grp.geometry if n in names[kind]]
        joints = {o.parentJoint for _, o, _ in objs}
        if len(joints) != 1:
            raise CapmapError(f"capsule {grp.name}: its geometry objects ride on different joints "
                              f"({', '.join(robot.model.names[j] for j in sorted(joints))})")
        members[grp.name] = objs
        joint_of[grp.name] = joints.pop()
        for kind, o, _ in objs:
            claimed[kind].add(o.name)
    fitted: dict[bytes, Capsule] = {}  # the same balls (in their joint's frame: the two arms' like links) fit once

    def fit_once(c: np.ndarray, r: np.ndarray) -> Capsule:
        key = np.ascontiguousarray(c).tobytes() + np.ascontiguousarray(r).tobytes()
        if key not in fitted:
            fitted[key] = fit_capsule(c, r)
        return fitted[key]

    # the objects no group names join the group on their joint whose first fit they stick out of least
    first: dict[str, Capsule] = {}  # fitted only where an object has more than one group to choose from
    for kind, gm in models.items():
        for o in gm.geometryObjects:
            if o.name in claimed[kind]:
                continue
            groups = [g for g in members if joint_of[g] == o.parentJoint]
            if not groups:
                raise CapmapError(f"{kind} object {o.name} rides on joint {robot.model.names[o.parentJoint]}, which no "
                                  "capsule group is on: name it in a group of the robot file's capsules")
            if len(groups) > 1:
                for g in groups:
                    if g not in first:
                        first[g] = fit_once(*_balls([(k, x) for k, x, named in members[g] if named])[:2])
                c, r = geometry_balls(o)
                groups = [min(groups, key=lambda g: float(_excess(first[g], c, r).max()))]
            members[groups[0]].append((kind, o, False))
    out, covered = [], {}
    order = {"left": 0, "right": 0, "body": 0}
    for grp in desc.groups:
        objs = members[grp.name]
        c, r, src = _balls([(k, o) for k, o, _ in objs])
        fit = np.isin(src, desc.cover)
        if not fit.any():
            raise CapmapError(f"capsule {grp.name}: none of its geometry is in the covered set {list(desc.cover)}")
        cap: Capsule = fit_once(c[fit], r[fit])
        joint = robot.model.names[joint_of[grp.name]]
        out.append(LinkCapsule(grp.name, grp.part, order[grp.part], joint, cap.a, cap.b, cap.r))
        order[grp.part] += 1
        covered[grp.name] = Covered(c, r, src, tuple(f"{k}:{o.name}{'' if named else '*'}" for k, o, named in objs))
    return DualArm(desc, robot.model, robot.geometry, robot.gripper_frames, robot.q_lower, robot.q_upper,
                   robot.v_max, tuple(out), robot.visual), covered
