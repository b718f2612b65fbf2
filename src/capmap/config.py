"""Run configuration: validated once against a JSON schema, then frozen dataclasses.

Stage slices (:func:`stage_slices`) are the parts of the config each pipeline stage
depends on; their canonical JSON goes into the Snakemake rule's ``params`` (so a change
reruns exactly the affected stages) and into each output's provenance.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from capmap.errors import CapmapError
from capmap.validation import load_yaml, validate


@dataclass(frozen=True)
class LockConfig:
    joint: int  # 1-based
    angle_deg: float


@dataclass(frozen=True)
class TaskConfig:
    orientation_rpy_deg: tuple[float, float, float]
    v_max_mps: float
    a_max_mps2: float
    payload_kg: tuple[float, ...]  # one or more task payloads; each is planned and verified
    start_m: tuple[float, float, float]
    goal_m: tuple[float, float, float]
    q_ini_deg: tuple[float, ...]

    @property
    def rotation(self) -> np.ndarray:
        return self.rotation_from_rpy(self.orientation_rpy_deg)

    @staticmethod
    def rotation_from_rpy(rpy_deg) -> np.ndarray:
        """R = Rz(yaw) Ry(pitch) Rx(roll) (3, 3) from [roll, pitch, yaw] deg."""
        import pinocchio as pin

        return pin.rpy.rpyToMatrix(*np.deg2rad(np.asarray(rpy_deg, dtype=float)))


@dataclass(frozen=True)
class LimitsConfig:
    joint_torque_nm: float | tuple[float, ...]
    base_force_n: float | tuple[float, ...]
    base_moment_nm: float | tuple[float, ...]

    def resolve(self, n_joints: int):
        """:class:`capmap.capacity.Limits` for an arm with n_joints joints (length checks here)."""
        from capmap.capacity import Limits

        return Limits(per_item(self.joint_torque_nm, n_joints, "limits.joint_torque_nm"),
                      per_item(self.base_force_n, 3, "limits.base_force_n"),
                      per_item(self.base_moment_nm, 3, "limits.base_moment_nm"))


def per_item(value, n: int, key: str) -> np.ndarray:
    """One value for all n items, or exactly n values (else a one-line error naming key)."""
    v = np.atleast_1d(np.asarray(value, dtype=float))
    if len(v) == 1:
        return np.full(n, v[0])
    if len(v) != n:
        raise CapmapError(f"{key} has {len(v)} values; give one or {n}")
    return v


@dataclass(frozen=True)
class SamplingConfig:
    mode: str
    n_points: int
    seed: int
    jitter_per_voxel: int = 1


@dataclass(frozen=True)
class DirectionsConfig:
    kind: str
    step_deg: float | None = None
    n: int | None = None

    def build(self):
        from capmap import directions

        return directions.paper_grid(self.step_deg) if self.kind == "paper_grid" else directions.sphere(self.n)


DEFAULT_DT_S = 0.1


@dataclass(frozen=True)
class RunConfig:
    robot: str
    lock: LockConfig
    task: TaskConfig
    limits: LimitsConfig
    sampling: SamplingConfig
    directions: DirectionsConfig
    voxel_edge_m: float
    shards: int
    dt_s: float = DEFAULT_DT_S  # verification sample spacing


def _tuple(v):
    return tuple(v) if isinstance(v, list) else v


def parse_config(doc: object, source: str = "config") -> RunConfig:
    """Validate a run-config mapping and turn it into a :class:`RunConfig`."""
    if not isinstance(doc, dict):
        raise CapmapError(f"{source}: the config must be a mapping of keys, got {type(doc).__name__}")
    validate(doc, "config", source)
    d = doc["directions"]
    if d["kind"] == "paper_grid" and "step_deg" not in d:
        raise CapmapError(f"{source}: directions.step_deg is required for kind paper_grid")
    if d["kind"] == "sphere" and "n" not in d:
        raise CapmapError(f"{source}: directions.n is required for kind sphere")
    extra = {"paper_grid": "n", "sphere": "step_deg"}[d["kind"]]
    if extra in d:
        raise CapmapError(f"{source}: directions.{extra} does not apply to kind {d['kind']}")
    task = {k: _tuple(v) for k, v in doc["task"].items()}
    task["payload_kg"] = tuple(float(m) for m in np.atleast_1d(task["payload_kg"]))
    labels = [payload_label(m) for m in task["payload_kg"]]
    if len(set(labels)) != len(labels):
        raise CapmapError(f"{source}: task.payload_kg has repeated values {labels}")
    limits = {k: _tuple(v) for k, v in doc["limits"].items()}
    return RunConfig(
        robot=doc["robot"],
        lock=LockConfig(**doc["lock"]),
        task=TaskConfig(**task),
        limits=LimitsConfig(**limits),
        sampling=SamplingConfig(**doc["sampling"]),
        directions=DirectionsConfig(**d),
        voxel_edge_m=float(doc["voxels"]["edge_m"]),
        shards=int(doc["shards"]),
        dt_s=float(doc.get("verification", {}).get("dt_s", DEFAULT_DT_S)),
    )


def load_config(path: str | Path) -> RunConfig:
    return parse_config(load_yaml(path), str(path))


def canonical(obj) -> str:
    """Canonical JSON (sorted keys, no spaces): equal configs give equal strings."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"))


def config_hash(obj) -> str:
    return hashlib.sha256(canonical(obj).encode()).hexdigest()[:16]


def payload_label(payload_kg: float) -> str:
    """File-name label of a payload: 1500 -> '1500', 1250.5 -> '1250.5'."""
    return f"{float(payload_kg):g}"


def stage_slices(doc: dict, payload_kg: float | None = None) -> dict[str, dict]:
    """Per-stage config slices: ``own`` (the keys a stage reads itself) and ``upstream`` (its
    own plus every earlier stage's: what its output depends on). ``upstream`` is what the
    Snakefile puts in the rule's params and what provenance records.

    model:    robot
    sample:   lock, sampling (+ voxels for voxel_fill, whose grid it fills)
    capacity: task orientation/speed/acceleration, limits, directions
    voxels:   voxels
    plan:     task payload/start/goal
    verify:   task payload/start/goal/q_ini, verification

    ``payload_kg``: the one payload a plan/verify job handles (the config may list several;
    each job depends on its own only, so adding a payload reruns nothing else).
    """
    task = dict(doc["task"])
    if payload_kg is not None:
        task["payload_kg"] = float(payload_kg)
    own = {
        "model": {"robot": doc["robot"]},
        "sample": {"lock": doc["lock"], "sampling": doc["sampling"],
                   **({"voxels": doc["voxels"]} if doc["sampling"]["mode"] == "voxel_fill" else {})},
        "capacity": {"task": {k: task[k] for k in ("orientation_rpy_deg", "v_max_mps", "a_max_mps2")},
                     "limits": doc["limits"], "directions": doc["directions"]},
        "voxels": {"voxels": doc["voxels"]},
        "plan": {"task": {k: task[k] for k in ("payload_kg", "start_m", "goal_m")}},
        "verify": {"task": {k: task[k] for k in ("payload_kg", "start_m", "goal_m", "q_ini_deg")},
                   "verification": {"dt_s": doc.get("verification", {}).get("dt_s", DEFAULT_DT_S)}},
    }
    order = ["model", "sample", "capacity", "voxels", "plan", "verify"]
    out, acc = {}, {}
    for stage in order:
        acc = {**acc, stage: own[stage]}
        out[stage] = {"own": own[stage], "upstream": dict(acc)}
    return out


FOLLOW_CASES = ("space", "ground")


def follow_slices(doc: dict) -> dict[str, dict]:
    """Config slice each follow case depends on (its rule's params). ``space`` follows the
    verified path of its payload, so it depends on everything that path depends on;
    ``ground`` is independent of the capacity pipeline."""
    fol = doc.get("follow", {})
    out = {}
    if "space" in fol:
        up = dict(stage_slices(doc, fol["space"]["payload_kg"])["verify"]["upstream"])
        up["verify"] = {"task": up["verify"]["task"]}  # q_ini, start, goal; not verification.dt_s
        out["space"] = {**up, "follow": {"period_s": fol["period_s"], "space": fol["space"]}}
    if "ground" in fol:
        out["ground"] = {"follow": {"period_s": fol["period_s"], "ground": fol["ground"]}}
    return out


def check_follow(doc: dict, run: RunConfig, source: str = "config") -> None:
    """The follow section's cross-checks (payload known, robot loads, lengths match)."""
    from capmap.robot import load

    fol = doc.get("follow", {})
    if "space" in fol and float(fol["space"]["payload_kg"]) not in run.task.payload_kg:
        raise CapmapError(f"{source}: follow.space.payload_kg = {fol['space']['payload_kg']:g} is not one of "
                          f"task.payload_kg {[f'{m:g}' for m in run.task.payload_kg]} (its verified path is followed)")
    if "ground" in fol:
        g = fol["ground"]
        robot = load(g["robot"])
        if len(g["q_start_deg"]) != robot.n_joints:
            raise CapmapError(f"{source}: follow.ground.q_start_deg has {len(g['q_start_deg'])} values but "
                              f"{robot.name} has {robot.n_joints} joints")
        per_item(g["joint_torque_nm"], robot.n_joints, "follow.ground.joint_torque_nm")
        if not np.linalg.norm(g["line_m"]) > 0:
            raise CapmapError(f"{source}: follow.ground.line_m must not be zero")
        from capmap import ik
        from capmap.locking import free

        arm = free(robot)
        T0 = arm.fk(np.deg2rad(np.asarray(g["q_start_deg"], dtype=float))[None])[0]
        end = T0[:3, 3] + np.asarray(g["line_m"], dtype=float)
        if ik.solve(arm, end[None], T0[:3, :3]).n_solutions[0] == 0:
            raise CapmapError(f"{source}: follow.ground.line_m = {g['line_m']} ends at "
                              f"[{', '.join(f'{v:.4g}' for v in end)}], which {robot.name} cannot reach at the "
                              f"start orientation")


def check_run_config(doc: dict, source: str = "config") -> RunConfig:
    """Everything that can be checked before any job: schema, robot file, lock, limits, directions."""
    from capmap.locking import lock
    from capmap.robot import load

    run = parse_config(doc, source)
    robot = load(run.robot)
    arm = lock(robot, run.lock.joint, np.deg2rad(run.lock.angle_deg))
    run.limits.resolve(robot.n_joints).vector(arm)
    run.directions.build()
    if len(run.task.q_ini_deg) != robot.n_joints:
        raise CapmapError(f"{source}: task.q_ini_deg has {len(run.task.q_ini_deg)} values but {robot.name} has "
                          f"{robot.n_joints} joints")
    if abs(run.task.q_ini_deg[run.lock.joint - 1] - run.lock.angle_deg) > 1e-9:
        raise CapmapError(f"{source}: task.q_ini_deg[{run.lock.joint - 1}] = {run.task.q_ini_deg[run.lock.joint - 1]:g} "
                          f"must equal lock.angle_deg = {run.lock.angle_deg:g} (joint {run.lock.joint} is locked)")
    check_task_poses(arm, run.task, source)
    check_follow(doc, run, source)
    return run


def check_task_poses(arm, task: TaskConfig, source: str = "config") -> None:
    """Start and goal reachable at the task orientation; q_ini an IK solution at the start."""
    from capmap import ik
    from capmap.verification import start_branch

    sol = ik.solve(arm, np.array([task.start_m, task.goal_m]), task.rotation)
    for key, n, x in zip(("start_m", "goal_m"), sol.n_solutions, (task.start_m, task.goal_m)):
        if n == 0:
            raise CapmapError(f"{source}: task.{key} = [{', '.join(f'{v:g}' for v in x)}] is not reachable by the "
                              f"locked arm at task.orientation_rpy_deg = {list(task.orientation_rpy_deg)}")
    try:
        start_branch(arm, np.asarray(task.start_m), task.rotation, np.deg2rad(np.asarray(task.q_ini_deg))[arm.active])
    except CapmapError as exc:
        raise CapmapError(f"{source}: {exc}") from None
