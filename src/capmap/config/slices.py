"""Stage slices: the part of the config each pipeline stage depends on.

Their canonical JSON goes into the Snakemake rule's ``params`` (so a change reruns exactly
the affected stages) and into each output's provenance.
"""

from __future__ import annotations

from capmap.config.capacity import DEFAULT_DT_S
from capmap.io.datasets import canonical, config_hash

__all__ = ["canonical", "config_hash", "payload_label", "stage_slices", "follow_slices", "reconfig_slices", "dualarm_slices", "STAGES"]

STAGES = ("model", "sample", "capacity", "voxels", "plan", "verify")  # the capacity family, in order


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
    out, acc = {}, {}
    for stage in STAGES:
        acc = {**acc, stage: own[stage]}
        out[stage] = {"own": own[stage], "upstream": dict(acc)}
    return out


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


def reconfig_slices(doc: dict) -> dict[str, dict]:
    """Config slice of each reconfiguration job: ``nullspace`` and ``pinv`` (which does not use
    kappa0) plan; ``animation`` also depends on its frame rate. Empty without a reconfig section."""
    rc = doc.get("reconfig")
    if rc is None:
        return {}
    plan = {k: v for k, v in rc.items() if k != "animation_fps"}
    return {"nullspace": {"reconfig": plan},
            "pinv": {"reconfig": {k: v for k, v in plan.items() if k != "kappa0"}},
            "animation": {"reconfig": rc}}


def dualarm_slices(doc: dict) -> dict[str, dict]:
    """Config slice of each dual-arm rule: the scan, the envelope (scan + fitting), the capsules
    (robot), the optimisation (envelope + capsules + horizon, weights, margin, solver, finer
    grid), the CSQP check (its own horizon), the animation (+ its frame rate). A cost weight
    changes the optimisation and the check, never the scan, envelope or capsules."""
    da = doc.get("dualarm")
    if da is None:
        return {}
    scan = {"scene": da["scene"], "cloud": da["cloud"]}
    envelope = {**scan, "fit": da.get("fit", {})}
    capsules = {"robot": da["robot"]}
    problem = {**envelope, **capsules, **{k: da[k] for k in ("weights", "solver")}}
    motion = {**problem, "margin_m": da["margin_m"], "horizon": da["horizon"], "fine_factor": da.get("fine_factor", 5)}
    check = {**problem, "check": da["check"]}  # its own horizon; no inequalities, so no margin
    return {"scan": {"dualarm": scan}, "envelope": {"dualarm": envelope}, "capsules": {"dualarm": capsules},
            "optimise": {"dualarm": motion}, "check": {"dualarm": check},
            "animation": {"dualarm": {**motion, "animation_fps": da.get("animation_fps", 25)}}}
