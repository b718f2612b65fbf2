"""Checks that need the robot, run once before any job: everything a stage would otherwise
find out late (the robot file builds, the lock, limit lengths, reachable start and goal, a
start configuration on an IK branch, the follow cases). Numerics raise in their own terms;
here their messages are re-worded with the config keys (:meth:`CapmapError.in_terms`)."""

from __future__ import annotations

import hashlib
import json
import os
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin

from capmap.capacity.build import directions_of, load_limits, refine_settings, resolve_failure, task_rotation
from capmap.capacity.sizing import estimate_map
from capmap.capacity.voxels import Grid
from capmap.config.capacity import DirectionsConfig, TaskConfig
from capmap.config.estimate import MapJobs, check_duration, check_steps, line_duration_s
from capmap.config.failure import Failure
from capmap.config.following import FollowConfig
from capmap.config.inputs import check_cloud_file
from capmap.config.jobs import PlanTask
from capmap.config.parse import parse_config
from capmap.config.robot_file import referenced_files
from capmap.config.run import RunConfig
from capmap.config.typed import per_item
from capmap.core import ik
from capmap.core.profiles import MIN_PHASE_INTERVALS
from capmap.core.reduction import LockedArm, free
from capmap.core.robot import Robot
from capmap.core.tracking import nearest_branch
from capmap.errors import CapmapError, ConfigError
from capmap.io.fingerprint import code_fingerprint, file_sha256
from capmap.robots import load

__all__ = ["check_run_config", "check_capacity_config", "check_goal", "check_dt", "check_follow",
           "check_on_grid", "check_motions",
           "check_dualarm", "dual_arm_limits"]


@contextmanager
def _named(source: str):
    """A ConfigError raised inside, prefixed with the config's name when it does not start with it."""
    try:
        yield
    except ConfigError as exc:
        if str(exc).startswith(f"{source}:"):
            raise
        raise ConfigError(f"{source}: {exc}") from None


def _map_keys(prefix: str, edge_key: str, directions: DirectionsConfig) -> dict[str, str]:
    """The config keys of a map's size (main map: prefix ''; the atlas': 'atlas.'), for estimate_map."""
    return {"n_points": f"{prefix}sampling.n_points", "edge_m": edge_key, "jitter": f"{prefix}sampling.jitter_per_voxel",
            "directions": f"{prefix}directions.{'n' if directions.kind == 'sphere' else 'step_deg'}"}


def check_capacity_config(doc: dict, source: str = "config") -> RunConfig:
    """The checks of the capacity map's part of a config (schema, robot file, lock, limits, directions,
    tasks, the map's size): what ``capmap query`` needs, without the other families' (their files)."""
    return _capacity_checked(doc, source)[0]


def check_run_config(doc: dict, source: str = "config") -> RunConfig:
    """Everything that can be checked before any job: schema, robot file, lock, limits, directions."""
    cfg, robot, arm, limits = _capacity_checked(doc, source)
    with _named(source):
        check_motions(cfg, cfg.failure, source)
    if cfg.follow is not None:
        with _named(source):
            check_follow(cfg.follow, cfg, source)
    if cfg.reconfig is not None:
        from capmap.reconfig.build import rate_limits, reconfig_problem  # here: a capacity query does not load it

        with _named(source):
            rate_limits(cfg.reconfig, reconfig_problem(cfg.reconfig))
    if cfg.atlas is not None:
        cfg.atlas.check(robot.name, np.rad2deg(robot.q_lower), np.rad2deg(robot.q_upper), source)
        keys = _map_keys("atlas.", "atlas.edge_m", cfg.atlas.directions)
        try:
            estimate_map(arm, cfg.atlas.sampling, cfg.atlas.edge_m, len(directions_of(cfg.atlas.directions)),
                         len(limits.names), MapJobs(1, False), keys)
        except ConfigError as exc:
            raise ConfigError(f"{source}: {exc}") from None
    if cfg.advice is not None:
        cfg.advice.check(robot.name, robot.n_joints, cfg.lock.joint, source)
    if cfg.dualarm is not None:
        check_dualarm(cfg, source)
    return cfg


def _capacity_checked(doc: dict, source: str) -> tuple[RunConfig, Robot, LockedArm, object]:
    """The config with its failure, estimate, limits and tasks resolved; the robot, the locked arm, its limits."""
    cfg = parse_config(doc, source)
    robot = load(cfg.robot)
    failure, arm = resolve_failure(robot, cfg.lock, cfg.task, source)
    try:
        limits_cfg = cfg.limits.for_robot(robot)  # the URDF's effort limits unless limits.joint_torque_nm
        limits = load_limits(limits_cfg, robot.n_joints).for_arm(arm)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    dirs = directions_of(cfg.directions)
    check_goal(arm, cfg.task, failure, source)
    tasks = check_tasks(cfg.tasks, arm, cfg.task, failure, source)
    check_dt(cfg, source)
    if cfg.refine is not None:
        try:
            refine_settings(cfg.refine, cfg.task.payload_kg)
        except ConfigError as exc:
            raise ConfigError(f"{source}: {exc}") from None
    keys = _map_keys("", "voxels.edge_m", cfg.directions)
    try:
        estimate, grid = estimate_map(arm, cfg.sampling, cfg.voxel_edge_m, len(dirs), len(limits.names),
                                      MapJobs(cfg.shards, cfg.refine is not None), keys)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    check_on_grid(cfg, failure, grid, source)
    return replace(cfg, failure=failure, estimate=estimate, limits=limits_cfg.canonical(), tasks=tasks), robot, arm, limits


def check_dt(cfg: RunConfig, source: str = "config") -> None:
    """verification.dt_s resolves the motion: at most a tenth of the acceleration phase (v/a)."""
    t_acc = cfg.task.v_max_mps / cfg.task.a_max_mps2
    if cfg.verification.dt_s > t_acc / MIN_PHASE_INTERVALS:
        raise ConfigError(f"{source}: verification.dt_s = {cfg.verification.dt_s:g} s is too coarse for the motion: its "
                          f"acceleration phase lasts task.v_max_mps / task.a_max_mps2 = {t_acc:.3g} s; use at most "
                          f"{t_acc / MIN_PHASE_INTERVALS:.3g} s ({MIN_PHASE_INTERVALS} samples per phase)")


def check_goal(arm: LockedArm, task: TaskConfig, failure: Failure, source: str = "config",
               goal_m=None, key: str = "task.goal_m") -> None:
    """The goal (``task.goal_m``, or ``goal_m`` named ``key``) reachable at the task orientation by
    the locked arm (the start is, by resolution)."""
    goal = task.goal_m if goal_m is None else goal_m
    start = failure.start_m if goal_m is None else None
    if start is not None and np.linalg.norm(np.subtract(goal, start)) < 1e-6:
        raise ConfigError(f"{source}: {key} = [{', '.join(f'{v:g}' for v in goal)}] is the start "
                          f"({'task.start_m' if failure.start_given else 'FK(task.q_ini_deg)'}): nothing to plan")
    if ik.solve(arm, np.asarray(goal, dtype=float)[None], task_rotation(task)).n_solutions[0] == 0:
        raise ConfigError(f"{source}: {key} = [{', '.join(f'{v:g}' for v in goal)}] is not reachable "
                          f"at task.orientation_rpy_deg = {list(task.orientation_rpy_deg)} with joint {failure.joint} "
                          f"locked at {failure.angle_deg:g} deg")


def check_tasks(tasks: tuple[PlanTask, ...], arm: LockedArm, task: TaskConfig, failure: Failure,
                source: str = "config") -> tuple[PlanTask, ...]:
    """``tasks``: distinct names, every start and goal reachable at the task's orientation; returns
    them with each start configuration resolved: the IK solution at its start nearest q_start_deg over
    the joints that still move (the locked joint's value is not used, so a lock edit alone keeps a
    task valid), every joint in deg with the locked one at the lock angle."""
    names = [t.name for t in tasks]
    if len(set(names)) < len(names):
        raise ConfigError(f"{source}: tasks: names must differ ({names})")
    out = []
    for i, t in enumerate(tasks):
        key = f"tasks[{i}] ({t.name})"
        if np.linalg.norm(np.subtract(t.goal_m, t.start_m)) < 1e-6:
            raise ConfigError(f"{source}: {key}.goal_m equals {key}.start_m: nothing to plan")
        q = np.asarray(t.q_start_deg, dtype=float)
        if len(q) != arm.robot.n_joints:
            raise ConfigError(f"{source}: {key}.q_start_deg has {len(q)} values but {arm.robot.name} has "
                              f"{arm.robot.n_joints} joints")
        sol = ik.solve(arm, np.asarray(t.start_m, dtype=float)[None], task_rotation(task))
        n = int(sol.n_solutions[0])
        if n == 0:
            raise ConfigError(f"{source}: {key}.start_m = [{', '.join(f'{v:g}' for v in t.start_m)}] is not reachable "
                              f"at task.orientation_rpy_deg = {list(task.orientation_rpy_deg)} with joint "
                              f"{failure.joint} locked at {failure.angle_deg:g} deg")
        _, q_branch, _ = nearest_branch(sol.q[0, :n], np.deg2rad(q)[arm.active])
        q_start = np.rad2deg(arm.full_q(q_branch))
        q_start[failure.joint - 1] = failure.angle_deg  # exactly as given, not through radians
        check_goal(arm, task, failure, source, t.goal_m, f"{key}.goal_m")
        out.append(replace(t, q_start_deg=tuple(float(v) for v in q_start)))
    return tuple(out)


def check_follow(fol: FollowConfig, cfg: RunConfig, source: str = "config") -> None:
    """The follow section's cross-checks (payload known, robot loads, lengths match, line reachable)."""
    if fol.store_period_s is not None and not fol.store_period_s >= fol.period_s:
        raise ConfigError(f"{source}: follow.store_period_s = {fol.store_period_s:g} s is shorter than follow.period_s = "
                          f"{fol.period_s:g} s: the stored series cannot be finer than the control; give at least "
                          "the control period")
    if fol.space is not None and float(fol.space.payload_kg) not in cfg.task.payload_kg:
        raise ConfigError(f"{source}: follow.space.payload_kg = {fol.space.payload_kg:g} is not one of "
                          f"task.payload_kg {[f'{m:g}' for m in cfg.task.payload_kg]} (its verified path is followed)")
    g = fol.ground
    if g is None:
        return
    robot = load(g.robot)
    if len(g.q_start_deg) != robot.n_joints:
        raise ConfigError(f"{source}: follow.ground.q_start_deg has {len(g.q_start_deg)} values but "
                          f"{robot.name} has {robot.n_joints} joints")
    per_item(g.joint_torque_nm, robot.n_joints, "follow.ground.joint_torque_nm")
    if not np.linalg.norm(g.line_m) >= 1e-3:
        raise ConfigError(f"{source}: follow.ground.line_m = {list(g.line_m)} is {np.linalg.norm(g.line_m):.3g} m long: "
                          "give a line of at least 1 mm")
    t_line = line_duration_s(float(np.linalg.norm(g.line_m)), g.v_max_mps, g.a_max_mps2)
    check_duration(t_line, "follow.ground.v_max_mps", "follow.ground.a_max_mps2", "follow.ground.line_m")
    check_steps(2 * t_line / fol.period_s, "follow.period_s",
                f"following follow.ground.line_m ({t_line:.3g} s) at follow.period_s = {fol.period_s:g} s")
    arm = free(robot)
    T0 = arm.fk(np.deg2rad(np.asarray(g.q_start_deg, dtype=float))[None])[0]
    end = T0[:3, 3] + np.asarray(g.line_m, dtype=float)
    if ik.solve(arm, end[None], T0[:3, :3]).n_solutions[0] == 0:
        raise ConfigError(f"{source}: follow.ground.line_m = {list(g.line_m)} ends at "
                          f"[{', '.join(f'{v:.4g}' for v in end)}], which {robot.name} cannot reach at the "
                          f"start orientation")


def check_on_grid(cfg: RunConfig, failure: Failure, grid: Grid | None, source: str = "config") -> None:
    """Every start and goal lies inside the map's grid (known before any job: the grid covers the
    seeded joint samples, as the voxels stage's will), else the planner could not place it."""
    if grid is None:
        return
    ends = [("task.start_m" if failure.start_given else "the start (FK(task.q_ini_deg))", failure.start_m),
            ("task.goal_m", cfg.task.goal_m)]
    ends += [(f"tasks[{i}] ({t.name}).{k}", getattr(t, k)) for i, t in enumerate(cfg.tasks) for k in ("start_m", "goal_m")]
    hi = grid.lower + np.asarray(grid.shape) * grid.edge_m
    for key, p in ends:
        if grid.index(np.asarray(p, dtype=float)[None])[0, 0] < 0:
            raise ConfigError(f"{source}: {key} = [{', '.join(f'{v:.4g}' for v in p)}] lies outside the map's grid "
                              f"[{', '.join(f'{v:.4g}' for v in grid.lower)}] .. [{', '.join(f'{v:.4g}' for v in hi)}] m, "
                              f"which covers the sampling.n_points = {cfg.sampling.n_points:,} joint samples: raise "
                              "sampling.n_points")


def check_motions(cfg: RunConfig, failure: Failure, source: str = "config") -> None:
    """The verified motions and the reconfiguration fit in MAX_STEPS samples (a planned path taken as
    at most ten times its direct line; the reconfiguration at its slowest time scale)."""
    v, a = cfg.task.v_max_mps, cfg.task.a_max_mps2
    lines = [(failure.start_m, cfg.task.goal_m)] + [(t.start_m, t.goal_m) for t in cfg.tasks]
    longest = max(line_duration_s(float(np.linalg.norm(np.subtract(g, s))), v, a) for s, g in lines)
    check_duration(longest, "task.v_max_mps", "task.a_max_mps2", "the task's straight lines")
    dt = cfg.verification.dt_s
    check_steps(10 * longest / dt, "verification.dt_s", f"verifying the task's motions at verification.dt_s = {dt:g} s")
    if cfg.follow is not None and cfg.follow.space is not None:
        check_steps(10 * longest / cfg.follow.period_s, "follow.period_s",
                    f"following the planned path at follow.period_s = {cfg.follow.period_s:g} s")
    rc = cfg.reconfig
    if rc is not None:
        check_steps(rc.duration_s / (rc.dt_s * rc.min_time_scale), "reconfig.dt_s",
                    f"the reconfiguration (reconfig.law.duration_s = {rc.duration_s:g} s) at reconfig.dt_s = {rc.dt_s:g} s")


def check_dualarm(cfg: RunConfig, source: str = "config") -> None:
    """The dual-arm files load, a user's cloud file is one the scan job can read, and the horizons
    and the synthetic scan fit."""
    from capmap.dualarm.scene_file import load_scene  # the dual-arm family's modules load only when it is checked

    da = cfg.dualarm
    scene = load_scene(da.scene)
    try:
        name, q_lower, q_upper = dual_arm_limits(da.robot, float(scene.panel.size[0]))
    except ConfigError:
        raise
    except CapmapError as exc:
        raise ConfigError(f"{source}: dualarm.robot = {da.robot!r} with dualarm.scene = {da.scene!r}: "
                          f"{exc.in_terms(urdf='its URDF')}") from None
    if len(scene.q_start) != len(q_lower) or np.any(scene.q_start < q_lower) or np.any(scene.q_start > q_upper):
        raise ConfigError(f"{source}: dualarm.scene = {da.scene!r}: start_configuration_rad is outside the joint limits "
                          f"of {name} (or has not {len(q_lower)} values)")
    with _named(source):
        _dualarm_sizes(da, scene)


def _memo_file(robot_file: str, thickness_m: float) -> Path | None:
    """Where a successful dual-arm build of ``robot_file`` holding a part ``thickness_m`` thick is remembered:
    named by the content of every file the build reads (the robot file, its URDF and meshes:
    :func:`capmap.config.robot_file.referenced_files`), the thickness, Pinocchio's version and the code that
    loads and builds it (:func:`capmap.io.fingerprint.code_fingerprint`), in capmap's cache folder (beside
    numba's); None when there is none."""
    base = os.environ.get("CAPMAP_NUMBA_BASE")
    if not base:
        return None
    h = hashlib.sha256(f"{pin.__version__} {thickness_m!r}".encode())
    for mod in ("capmap.dualarm.scene.robot", "capmap.config.dualarm"):
        h.update(f" {mod} {code_fingerprint(mod)}".encode())
    for f in referenced_files(robot_file):
        h.update(f" {Path(f).resolve()} {file_sha256(f)}".encode())
    return Path(base) / "checks" / f"dual-arm-{h.hexdigest()[:24]}.json"


def dual_arm_limits(robot_file: str, thickness_m: float) -> tuple[str, np.ndarray, np.ndarray]:
    """(the robot's name, its joint limits lower, upper (n,) rad) when the dual-arm robot of ``robot_file``
    builds with its fingers closed on a part ``thickness_m`` thick (:func:`build_dual_arm`: the URDF, every
    collision and visual mesh, the joints and frames the file names); its errors as they are. The build
    loads every visual mesh (~1.4 s for the default robot): a success is remembered (:func:`_memo_file`), so
    the runs after the first that build the same robot from the same files and code read it instead."""
    from capmap.dualarm.build import load_dual_arm_file
    from capmap.dualarm.scene.robot import build_dual_arm

    desc = load_dual_arm_file(robot_file)  # first: the files' own checks (regular, bounded, found) before hashing them
    memo = _memo_file(robot_file, thickness_m)
    if memo is not None and memo.is_file():
        try:
            d = json.loads(memo.read_text())
            return str(d["name"]), np.asarray(d["q_lower"], float), np.asarray(d["q_upper"], float)
        except (OSError, ValueError, KeyError, TypeError):
            pass  # unreadable: built again (and written again)
    robot = build_dual_arm(desc, thickness_m)
    out = robot.description.name, robot.q_lower, robot.q_upper
    if memo is not None:
        try:
            memo.parent.mkdir(parents=True, exist_ok=True)
            tmp = memo.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(json.dumps({"name": out[0], "q_lower": out[1].tolist(), "q_upper": out[2].tolist()}))
            tmp.replace(memo)
        except OSError:
            pass  # a read-only cache: built each time
    return out


def _dualarm_sizes(da, scene) -> None:
    """The user's cloud file readable; the horizons, the re-check grid and the synthetic scan fit."""
    from capmap.dualarm.build import cloud_span_m, unknown_settings
    from capmap.dualarm.scene.solids import surface_points

    if da.cloud_file is not None:
        check_cloud_file(da.cloud_file, viewpoints=len(da.scan.viewpoints_m))
    u = unknown_settings(da.unknown)
    n_vox = float(np.prod(np.ceil((u.work_upper - u.work_lower) / u.voxel_m)))
    check_steps(n_vox, "dualarm.unknown.voxel_m", f"a carving grid of {n_vox:.3g} voxels of {u.voxel_m:g} m over "
                "dualarm.unknown.work_volume_m", "raise")
    for key, h in (("dualarm.horizon.nodes", da.horizon), ("dualarm.check.nodes", da.check.horizon)):
        check_steps(h.nodes * 100, key, f"an optimal control problem of {h.nodes:,} nodes (~100 steps of work each)",
                    "lower")
    check_steps(da.horizon.nodes * da.fine_factor, "dualarm.fine_factor",
                f"the re-check on a {da.fine_factor}x finer grid of {da.horizon.nodes:,} nodes", "lower")
    coarse = 0.05  # points scale with 1 / spacing^2: count them at a coarse spacing
    surface = surface_points(scene, coarse)[0]
    cloud_span_m(da, surface)  # the cloud's values, its noise and the fit's grid
    if da.cloud_file is None:
        n = len(surface) * (coarse / min(da.scan.spacing_m, coarse)) ** 2
        check_steps(n, "dualarm.cloud.spacing_m", f"a synthetic scan at dualarm.cloud.spacing_m = {da.scan.spacing_m:g} m "
                    f"(~{n:.3g} surface points)")
