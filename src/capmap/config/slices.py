"""Stage slices: the part of the config each pipeline stage depends on.

Their canonical JSON goes into the Snakemake rule's ``params`` (so a change reruns exactly
the affected stages) and into each output's provenance.
"""

from __future__ import annotations

import numpy as np

from capmap.config.capacity import DEFAULT_DT_S, GAIN_TASKS, PLAN_MOVES, refine_doc
from capmap.config.robot_file import referenced_files
from capmap.io.datasets import canonical, config_hash
from capmap.io.fingerprint import file_fingerprints

__all__ = ["task_slices", "canonical", "config_hash", "payload_label", "stage_slices", "follow_slices", "reconfig_slices",
           "dualarm_slices",
           "atlas_slices", "STAGES"]

STAGES = ("model", "sample", "capacity", "voxels", "refine", "plan", "verify")  # the capacity family, in order


def payload_label(payload_kg: float) -> str:
    """File-name label of a payload: 1500 -> '1500', 1250.5 -> '1250.5'."""
    return f"{float(payload_kg):g}"


def files_of(*paths) -> dict[str, str]:
    """Content fingerprints of the given robot/scene/cloud files and the URDFs they name (the
    part of a slice that makes an edited file rerun its stages even with an old date)."""
    return file_fingerprints([f for p in paths if p for f in referenced_files(p) if f.is_file()])


def per_item_canonical(section: dict) -> dict:
    """A section of one-or-per-item values (limits) with a list of equal values written as the
    one value: ``[700] * 7`` and ``700`` are the same limits, so the same slice."""
    return {k: (v[0] if isinstance(v, list) and v and all(x == v[0] for x in v) else v) for k, v in section.items()}


def _plan_slice(task: dict, moves: str) -> dict:
    """What a plan depends on: the task's payload, start and goal, the kind of moves and, for
    moves on the executed branch, the start configuration (it picks the branch)."""
    keys = ("payload_kg", "start_m", "goal_m") + (("q_start_deg",) if moves == "branch" else ())
    return {"task": {k: task[k] for k in keys}, "planning": {"moves": moves}}


def stage_slices(doc: dict, payload_kg: float | None = None) -> dict[str, dict]:
    """Per-stage config slices: ``own`` (the keys a stage reads itself) and ``upstream`` (its
    own plus every earlier stage's: what its output depends on). ``upstream`` is what the
    Snakefile puts in the rule's params and what provenance records.

    model:    robot
    sample:   lock, sampling (+ voxels for voxel_fill, whose grid it fills)
    capacity: task orientation/speed/acceleration, limits, directions
    voxels:   voxels.edge_m
    refine:   voxels.refine and the task payloads (voxels near a payload are refined further)
    plan:     task payload/start/goal, planning.moves (branch: also the start configuration)
    gain:     the map (refine upstream), payloads, planning.gain_tasks, verification.dt_s
    verify:   task payload/start/goal/start configuration, verification

    ``doc`` is the resolved document (:func:`capmap.config.failure.resolved_doc`): the lock angle
    and the start filled in, the start configuration as ``task.q_start_deg``. So a change of
    ``task.q_ini_deg`` reruns only what its resolution changes.

    ``payload_kg``: the one payload a plan/verify job handles (the config may list several;
    each job depends on its own only, so adding a payload reruns nothing else).
    """
    task = dict(doc["task"])
    edge = doc["voxels"]["edge_m"]
    refine = refine_doc(doc["voxels"])
    payloads = sorted(float(m) for m in np.atleast_1d(doc["task"]["payload_kg"]))  # every payload of the task
    if payload_kg is not None:
        task["payload_kg"] = float(payload_kg)
    own = {
        "model": {"robot": doc["robot"], "files": files_of(doc["robot"])},
        "sample": {"lock": doc["lock"], "sampling": doc["sampling"],
                   **({"voxels": {"edge_m": edge}} if doc["sampling"]["mode"] == "voxel_fill" else {})},
        "capacity": {"task": {k: task[k] for k in ("orientation_rpy_deg", "v_max_mps", "a_max_mps2")},
                     "limits": per_item_canonical(doc["limits"]), "directions": doc["directions"]},
        "voxels": {"voxels": {"edge_m": edge}},
        # refinement sharpens voxels near every task payload: it depends on the list, not on one job's payload
        "refine": {"refine": refine, **({"payloads_kg": payloads} if refine is not None else {})},
        "plan": _plan_slice(task, doc.get("planning", {}).get("moves", PLAN_MOVES[0])),
        # every payload x random (start, goal) pairs: isotropic against direction-aware moves, verified
        "gain": {"payloads_kg": payloads,
                 "gain_tasks": doc.get("planning", {}).get("gain_tasks", GAIN_TASKS),
                 "verification": {"dt_s": doc.get("verification", {}).get("dt_s", DEFAULT_DT_S)}},
        "verify": {"task": {k: task[k] for k in ("payload_kg", "start_m", "goal_m", "q_start_deg", "name") if k in task},
                   "verification": {"dt_s": doc.get("verification", {}).get("dt_s", DEFAULT_DT_S)}},
    }
    out, acc = {}, {}
    for stage in STAGES:
        acc = {**acc, stage: own[stage]}
        out[stage] = {"own": own[stage], "upstream": dict(acc)}
    out["gain"] = {"own": own["gain"], "upstream": {**out["refine"]["upstream"], "gain": own["gain"]}}  # not the task's
    return out


def follow_slices(doc: dict) -> dict[str, dict]:
    """Config slice each follow case depends on (its rule's params). ``space`` follows the
    verified path of its payload, so it depends on everything that path depends on;
    ``ground`` is independent of the capacity pipeline."""
    fol = doc.get("follow", {})
    out = {}
    if "space" in fol:
        up = dict(stage_slices(doc, fol["space"]["payload_kg"])["verify"]["upstream"])
        up["verify"] = {"task": up["verify"]["task"]}  # start configuration, start, goal; not verification.dt_s
        out["space"] = {**up, "follow": {"period_s": fol["period_s"], "space": fol["space"]}}
    if "ground" in fol:
        out["ground"] = {"follow": {"period_s": fol["period_s"], "ground": fol["ground"]},
                         "files": files_of(fol["ground"]["robot"])}
    return out


def reconfig_slices(doc: dict) -> dict[str, dict]:
    """Config slice of each reconfiguration job: ``nullspace`` and ``pinv`` (which does not use
    kappa0) plan; ``animation`` also depends on its frame rate. Empty without a reconfig section."""
    rc = doc.get("reconfig")
    if rc is None:
        return {}
    plan = {k: v for k, v in rc.items() if k != "animation_fps"}
    files = files_of(rc["robot"])
    return {"nullspace": {"reconfig": plan, "files": files},
            "pinv": {"reconfig": {k: v for k, v in plan.items() if k != "kappa0"}, "files": files},
            "animation": {"reconfig": rc, "files": files}}


def dualarm_slices(doc: dict) -> dict[str, dict]:
    """Config slice of each dual-arm rule: the scan, the envelope (scan + fitting), the capsules
    (robot), the optimisation (envelope + capsules + horizon, weights, margin, solver, finer
    grid), the CSQP check (its own horizon), the animation (+ its frame rate). A cost weight
    changes the optimisation and the check, never the scan, envelope or capsules."""
    da = doc.get("dualarm")
    if da is None:
        return {}
    scan = {"scene": da["scene"], "cloud": da["cloud"], "scene_files": files_of(da["scene"], da["cloud"].get("file"))}
    envelope = {**scan, "fit": da.get("fit", {})}
    capsules = {"robot": da["robot"], "robot_files": files_of(da["robot"])}
    problem = {**envelope, **capsules, **{k: da[k] for k in ("weights", "solver")}}
    motion = {**problem, "margin_m": da["margin_m"], "horizon": da["horizon"], "fine_factor": da.get("fine_factor", 5)}
    check = {**problem, "check": da["check"]}  # its own horizon; no inequalities, so no margin
    return {"scan": {"dualarm": scan}, "envelope": {"dualarm": envelope}, "capsules": {"dualarm": capsules},
            "optimise": {"dualarm": motion}, "check": {"dualarm": check},
            "animation": {"dualarm": {**motion, "animation_fps": da.get("animation_fps", 25)}}}


def atlas_slices(doc: dict) -> dict[str, dict]:
    """Config slice of the atlas rules (``doc`` resolved): a map depends on the robot, the task
    (its start resolved for each lock in the job), the limits, the atlas' sampling, directions and
    voxel edge, and verification.dt_s (its direct line), not on which joints and angles the atlas
    lists; the atlas table on all of that and the lists. Empty without an atlas section."""
    at = doc.get("atlas")
    if at is None:
        return {}
    task = {k: doc["task"][k] for k in ("orientation_rpy_deg", "v_max_mps", "a_max_mps2", "payload_kg", "start_m",
                                        "goal_m", "q_ini_deg")}
    one = {"model": {"robot": doc["robot"], "files": files_of(doc["robot"])}, "task": task,
           "limits": per_item_canonical(doc["limits"]),
           "verification": {"dt_s": doc.get("verification", {}).get("dt_s", DEFAULT_DT_S)},
           "atlas": {k: at[k] for k in ("sampling", "directions", "edge_m")}}
    return {"map": one, "atlas": {**one, "atlas": at}}


def task_slices(doc: dict) -> dict[str, dict]:
    """The plan and verify slices (upstream) of each further task of ``tasks``, by name: the
    main task's with its start, goal, payload and start configuration (and its name)."""
    out = {}
    for t in doc.get("tasks", []):
        sub = {**doc, "task": {**doc["task"], **{k: t[k] for k in ("start_m", "goal_m", "q_start_deg", "name")}}}
        sl = stage_slices(sub, float(t["payload_kg"]))
        out[t["name"]] = {"plan": sl["plan"]["upstream"], "verify": sl["verify"]["upstream"]}
    return out
