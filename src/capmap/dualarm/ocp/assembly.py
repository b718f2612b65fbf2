"""Put the dual-arm problem together: the panel held by both grippers, every swept volume on its
joint, the pairs worth checking, the panel's reference path, a warm start by inverse
kinematics along it, and the feasibility of the key poses.

Pairs checked (a pair of volumes that can never touch, or are meant to, is left out):
- capsules of one arm ``self_gap`` or more places apart along it (not two on the same joint;
  nearer ones overlap at their joints by design);
- every left capsule against every right capsule;
- arm capsules (but the first ``body_skip`` of each arm) against the static body;
- arm capsules against every volume of the environment;
- the panel against the environment, except the pins inside the pin zone (its holes slide
  over them: the insertion constraints keep them aligned), and against the arm capsules
  that do not hold it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from capmap.dualarm.geometry.collision import CollisionModel, Pairs, Primitives
from capmap.dualarm.ocp.settings import StopRule
from capmap.dualarm.ocp.task import AssemblyTask
from capmap.dualarm.scene.cloud import Envelope
from capmap.dualarm.scene.robot import DualArm
from capmap.dualarm.scene.solids import Scene

__all__ = ["Assembly", "assemble", "candidate_pairs", "reference_path", "IK_STOP", "arm_ik", "warm_start", "clearance_at"]

OBJ = object
IK_STOP = StopRule(60, 1e-10)  # arm_ik: Newton steps at most, and the pose error norm (m and rad) that ends them


@dataclass(frozen=True, eq=False)
class Assembly:
    """Everything the optimiser needs: the model (with a 'panel' frame), the task, the collision
    model, the candidate pairs and, per primitive, what it belongs to."""

    model: pin.Model
    task: AssemblyTask
    collision: CollisionModel
    pairs: Pairs
    q_start: np.ndarray
    panel_radius: float


def _segments(joint, a, b, r, body):
    n = len(a)
    z = np.zeros
    return Primitives(np.full(n, joint) if np.isscalar(joint) else np.asarray(joint), np.asarray(a, float).reshape(-1, 3),
                      np.asarray(b, float).reshape(-1, 3), np.asarray(r, float).reshape(-1),
                      np.asarray(body, dtype=OBJ).reshape(-1), z(0, int), z((0, 3, 3)), z(0), z(0, dtype=OBJ))


def _triangles(joint, v, r, body):
    z = np.zeros
    n = len(v)
    return Primitives(z(0, int), z((0, 3)), z((0, 3)), z(0), z(0, dtype=OBJ),
                      np.full(n, joint) if np.isscalar(joint) else np.asarray(joint), np.asarray(v, float).reshape(-1, 3, 3),
                      np.asarray(r, float).reshape(-1), np.asarray(body, dtype=OBJ).reshape(-1))


def reference_path(scene: Scene, N: int, n_transfer: int) -> tuple[pin.SE3, ...]:
    """The panel's reference poses at nodes 0..N: start -> pre-insertion (nodes 0..n_transfer) and
    pre-insertion -> final, each a screw-free interpolation (position straight, rotation by
    its log) on a quintic time law, rest to rest."""
    def leg(M0, M1, n):
        s = np.linspace(0, 1, n + 1)
        s = s**3 * (10 - 15 * s + 6 * s * s)
        dR = pin.log3(M0[:3, :3].T @ M1[:3, :3])
        return [pin.SE3(M0[:3, :3] @ pin.exp3(x * dR), M0[:3, 3] + x * (M1[:3, 3] - M0[:3, 3])) for x in s]
    first = leg(scene.start, scene.pre_insertion, n_transfer)
    return tuple(first + leg(scene.pre_insertion, scene.final, N - n_transfer)[1:])


def assemble(robot: DualArm, scene: Scene, env: Envelope, env_labels: tuple[np.ndarray, np.ndarray], N: int,
             dt: float, n_transfer: int) -> Assembly:
    """The model with the panel attached to the left gripper as it is held at the start, and the task."""
    model = robot.model.copy()
    data = model.createData()
    q0 = scene.q_start
    pin.framesForwardKinematics(model, data, q0)
    fl, fr = robot.gripper_frames["left"], robot.gripper_frames["right"]
    ML = data.oMf[fl]
    grasp = ML.actInv(pin.SE3(scene.start))  # panel in the left gripper's frame
    gframe = model.frames[fl]
    fp = model.addFrame(pin.Frame("panel", gframe.parentJoint, fl, gframe.placement * grasp, pin.FrameType.OP_FRAME))
    axis = scene.axis_direction
    e1 = np.cross(axis, [0, 0, 1.0]) if abs(axis[2]) < 0.9 else np.cross(axis, [1.0, 0, 0])
    e1 /= np.linalg.norm(e1)
    task = AssemblyTask(N, dt, n_transfer, fl, fr, fp, ML.actInv(data.oMf[fr]), pin.SE3(scene.pre_insertion),
                        pin.SE3(scene.final), scene.axis_point.copy(), np.array([e1, np.cross(axis, e1)]),
                        reference_path(scene, N, n_transfer))
    # -- primitives: robot capsules, the panel, the environment (faces, their edges, capsules)
    jid = {name: model.getJointId(name) for name in robot.joint_names}
    caps = robot.capsules
    robot_seg = _segments([jid.get(c.joint, 0) for c in caps], [c.a for c in caps], [c.b for c in caps],
                          [c.r for c in caps], [c.name for c in caps])
    panel_M = gframe.placement * grasp  # panel in its joint's frame
    corners = scene.panel.corners() @ panel_M.rotation.T + panel_M.translation
    r_panel = float(scene.panel.size[0] / 2)
    panel = Primitives.concat([
        _segments(gframe.parentJoint, corners, np.roll(corners, -1, axis=0), np.full(4, r_panel), ["panel"] * 4),
        _triangles(gframe.parentJoint, [corners[[0, 1, 2]], corners[[0, 2, 3]]], [r_panel] * 2, ["panel"] * 2)])
    tri_names, seg_names = env_labels
    edges = np.concatenate([env.tri[:, [0, 1, 2]], env.tri[:, [1, 2, 0]]], axis=0).reshape(2, -1, 3, 3)
    env_prims = Primitives.concat([
        _segments(0, env.seg[:, 0], env.seg[:, 1], env.seg_radius, seg_names),
        _segments(0, edges[0].reshape(-1, 3), edges[1].reshape(-1, 3), np.repeat(env.tri_radius, 3),
                  np.repeat(tri_names, 3)),
        _triangles(0, env.tri, env.tri_radius, tri_names)])
    prims = Primitives.concat([robot_seg, panel, env_prims])
    pairs = candidate_pairs(robot, scene, env, len(panel.seg_a))
    return Assembly(model, task, CollisionModel(model, prims), pairs, q0.copy(), r_panel)


def candidate_pairs(robot: DualArm, scene: Scene, env: Envelope, n_panel_edges: int = 4) -> Pairs:
    """The pairs of the module docstring, as indices into the primitives built by :func:`assemble`
    (robot capsules, panel edges, panel triangles, environment capsules, face edges, faces)."""
    caps = robot.capsules
    nc, S, T = len(caps), len(env.seg), len(env.tri)
    panel_e = np.arange(nc, nc + n_panel_edges)
    panel_t = np.arange(2)
    env_s = np.arange(nc + n_panel_edges, nc + n_panel_edges + S)
    env_e = np.arange(env_s[-1] + 1 if S else nc + n_panel_edges, nc + n_panel_edges + S + 3 * T)
    env_t = np.arange(2, 2 + T)
    lo, hi = scene.pin_zone
    seg_in_zone = np.all((env.seg >= lo) & (env.seg <= hi), axis=(1, 2)) if S else np.zeros(0, bool)
    tri_in_zone = np.all((env.tri >= lo) & (env.tri <= hi), axis=(1, 2)) if T else np.zeros(0, bool)
    desc = robot.description
    arm = {side: [i for i, c in enumerate(caps) if c.part == side] for side in ("left", "right")}
    body = [i for i, c in enumerate(caps) if c.part == "body"]
    ss, st = [], []
    for side, idx in arm.items():
        for x in range(len(idx)):
            for y in range(x + desc.self_gap, len(idx)):
                if caps[idx[x]].joint != caps[idx[y]].joint:
                    ss.append((idx[x], idx[y]))
        ss += [(i, b) for i in idx[desc.body_skip:] for b in body]
    ss += [(i, j) for i in arm["left"] for j in arm["right"]]
    movers = arm["left"] + arm["right"]
    ss += [(i, s) for i in movers for s in env_s]
    st += [(i, t) for i in movers for t in env_t]
    holders = {i for idx in arm.values() for i in idx[len(idx) - desc.hold:]}
    st += [(i, t) for i in movers if i not in holders for t in panel_t]
    # the panel against the environment: its edges vs faces, face edges vs the panel, capsules vs the panel
    st += [(e, t) for e in panel_e for k, t in enumerate(env_t) if not tri_in_zone[k]]
    st += [(e, t) for k in range(T) if not tri_in_zone[k] for e in env_e[3 * k:3 * k + 3] for t in panel_t]
    st += [(s, t) for k, s in enumerate(env_s) if not seg_in_zone[k] for t in panel_t]
    return Pairs(np.array(ss, dtype=int).reshape(-1, 2), np.array(st, dtype=int).reshape(-1, 2))


def arm_ik(model: pin.Model, data: pin.Data, frame: int, target: pin.SE3, q: np.ndarray, cols: slice,
           stop: StopRule = IK_STOP) -> tuple[np.ndarray, float]:
    """Damped least-squares Newton on one arm's joints (``cols`` of q (nq,) rad) to put ``frame`` at ``target``:
    the smallest joint change (no null-space motion), so a path stays continuous; at most ``stop.iterations``
    steps, ended once the pose error norm is below ``stop.tolerance``; returns (q, final pose error norm)."""
    iters, tol = stop.iterations, stop.tolerance
    q = q.copy()
    for _ in range(iters):
        pin.framesForwardKinematics(model, data, q)
        err = pin.log6(data.oMf[frame].actInv(target)).vector
        if np.linalg.norm(err) < tol:
            break
        pin.computeJointJacobians(model, data, q)
        J = pin.getFrameJacobian(model, data, frame, pin.ReferenceFrame.LOCAL)[:, cols]
        step = J.T @ np.linalg.solve(J @ J.T + 1e-8 * np.eye(6), err)
        q[cols] += np.clip(step, -0.3, 0.3)
    pin.framesForwardKinematics(model, data, q)
    return q, float(np.linalg.norm(pin.log6(data.oMf[frame].actInv(target)).vector))


def warm_start(asm: Assembly) -> np.ndarray:
    """Joint paths (N + 1, nq) holding the panel on its reference path, each node by inverse
    kinematics of both arms from the previous node (the closed chain is exact by construction)."""
    model, task = asm.model, asm.task
    data = model.createData()
    pin.framesForwardKinematics(model, data, asm.q_start)
    grasp = data.oMf[task.left].actInv(data.oMf[task.panel])  # panel in the left gripper
    half = model.nq // 2
    qs = [asm.q_start.copy()]
    for M_P in task.reference[1:]:
        ML = M_P * grasp.inverse()
        q, _ = arm_ik(model, data, task.left, ML, qs[-1], slice(0, half))
        q, _ = arm_ik(model, data, task.right, ML * task.rel_ref, q, slice(half, model.nq))
        qs.append(q)
    return np.array(qs)


def clearance_at(asm: Assembly, q: np.ndarray, node: int, iters: int = 40) -> tuple[np.ndarray, float, str]:
    """The configuration of node ``node``'s panel pose (both grippers fixed) with the most clearance
    over the arms' self-motion, from q: projected gradient steps on the smallest safety
    distance in the null space of both grippers' Jacobians, each followed by inverse kinematics
    back onto the grippers' poses. Returns (q, its smallest safety distance m, that pair)."""
    model, task = asm.model, asm.task
    data = model.createData()
    half = model.nq // 2
    pin.framesForwardKinematics(model, data, q)
    targets = (data.oMf[task.left].copy(), data.oMf[task.right].copy())
    best = None
    for _ in range(iters):
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        ev = asm.collision.evaluate(data, asm.pairs, gradient=True)
        k = int(np.argmin(ev.distance))
        if best is None or ev.distance[k] > best[1]:
            best = (q.copy(), float(ev.distance[k]), f"{ev.first[k]} vs {ev.second[k]}")
        near = ev.distance < ev.distance[k] + 0.005  # the nearest pairs move together
        g = ev.gradient[near].sum(axis=0)
        J = np.zeros((12, model.nq))
        J[:6, :half] = pin.getFrameJacobian(model, data, task.left, pin.ReferenceFrame.LOCAL)[:, :half]
        J[6:, half:] = pin.getFrameJacobian(model, data, task.right, pin.ReferenceFrame.LOCAL)[:, half:]
        step = g - np.linalg.pinv(J) @ (J @ g)
        if np.linalg.norm(step) < 1e-9:
            break
        q = q + 0.02 * step / np.linalg.norm(step)
        q, _ = arm_ik(model, data, task.left, targets[0], q, slice(0, half))
        q, _ = arm_ik(model, data, task.right, targets[1], q, slice(half, model.nq))
    return best
