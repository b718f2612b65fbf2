"""The typed configuration's path to a job: each stage's slice holds exactly the fields it declares
(and those of the stages before it), the job rebuilds the same types from it, and a field it did
not declare raises instead of being silently read."""

import copy
import json

import pytest
import yaml

from capmap.checks import check_run_config
from capmap.config import canonical, main_task, stage_config, stage_slice
from capmap.config.run import RunConfig
from capmap.config.slices import STAGES, upstream_fields
from capmap.config.typed import Undeclared, partial, to_doc
from capmap.errors import CapmapError
from tests.scenario import ROOT


@pytest.fixture(scope="module")
def doc():
    return yaml.safe_load((ROOT / "config" / "config.yaml").read_text())


@pytest.fixture(scope="module")
def cfg(doc):
    return check_run_config(copy.deepcopy(doc))


def _job(cfg, stage):
    return main_task(cfg.task, cfg.failure, cfg.task.payload_kg[0]) if any(
        p == "job" or p.startswith("job.") for p in upstream_fields(cfg, stage)) else None


def _leaves(d, prefix=""):
    for k, v in d.items():
        path = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict) and v and not path.endswith("configuration_deg"):
            yield from _leaves(v, path)
        else:
            yield path


def test_the_whole_config_round_trips_through_json(cfg):
    back = partial(RunConfig, json.loads(canonical(to_doc(cfg))))
    assert canonical(to_doc(back)) == canonical(to_doc(cfg))
    assert back.task.orientation_rpy_deg == cfg.task.orientation_rpy_deg and len(back.dualarm.weights.control) == 14


@pytest.mark.parametrize("stage", list(STAGES))
def test_a_slice_holds_exactly_the_declared_fields(cfg, stage):
    sl = stage_slice(cfg, stage, _job(cfg, stage))
    declared = set(upstream_fields(cfg, stage))
    found = {f"job.{p}" for p in _leaves(sl.get("job", {}))} | set(_leaves(sl.get("run", {})))
    # every leaf lies under a declared path, and every declared path is present
    assert all(any(f == d or f.startswith(d + ".") for d in declared) for f in found), (found, declared)
    assert all(any(f == d or f.startswith(d + ".") for f in found) or d == "job" and "job" in sl for d in declared)


@pytest.mark.parametrize("stage", list(STAGES))
def test_the_job_rebuilds_its_fields_and_refuses_the_others(cfg, stage):
    job = _job(cfg, stage)
    sl = stage_slice(cfg, stage, job)
    sc = stage_config(canonical(sl))
    assert canonical(stage_slice(cfg, stage, job)) == canonical(sl)  # deterministic
    for path in upstream_fields(cfg, stage):
        root, sub = (sc.job, path[4:]) if path.startswith("job") else (sc.run, path)
        value = root
        for name in filter(None, sub.split(".")):
            value = getattr(value, name)
        assert not isinstance(value, Undeclared), path
    undeclared = [f for f in ("name", "shards", "follow", "dualarm", "atlas", "sampling", "task")
                  if not any(p == f or p.startswith(f + ".") for p in upstream_fields(cfg, stage))]
    for f in undeclared:
        with pytest.raises(CapmapError, match=f"config field {f} is not in this stage's slice"):
            float(getattr(sc.run, f))


@pytest.mark.parametrize("edit, changed", [
    # (the further tasks are in the advice's slice only: each plan job holds its own task)
    (lambda d: d.update(tasks=[]) or d["lock"].update(angle_deg=101), {"sample", "advice_tasks"}),
    (lambda d: d["task"].update(goal_m=[2.625, 1.875, 4.125]), {"plan", "view", "atlas_map", "advice_tasks",
                                                                  "tolerant"}),
    (lambda d: d["verification"].update(dt_s=0.05), {"verify", "gain", "atlas_map", "advice_tasks"}),
    (lambda d: d["directions"].update(kind="paper_grid", step_deg=15), {"capacity", "lock_sweep"}),
    (lambda d: d["planning"].update(gain_tasks=3), {"gain"}),
    (lambda d: d["dualarm"]["weights"].update(panel=0.02), {"dualarm_problem"}),
    (lambda d: d["dualarm"].update(margin_m=0.004), {"dualarm_optimise"}),
    (lambda d: d["reconfig"].update(kappa0=0.0003), {"reconfig_nullspace"}),
    (lambda d: d["follow"]["ground"].update(catch_up_hz=4), {"follow_ground"}),
])
def test_an_edit_changes_the_slices_of_exactly_the_stages_that_read_it(doc, cfg, edit, changed):
    d2 = copy.deepcopy(doc)
    edit(d2)
    cfg2 = check_run_config(d2)
    differ = {s for s in STAGES
              if canonical(stage_slice(cfg, s, _job(cfg, s))) != canonical(stage_slice(cfg2, s, _job(cfg2, s)))}
    downstream = {s for s in STAGES if any(c in _ancestors(s) for c in changed)}
    assert differ == changed | downstream


def _ancestors(stage):
    out = {stage}
    for before in STAGES[stage].after:
        out |= _ancestors(before)
    return out


def test_an_undeclared_field_raises_on_comparison_and_formatting_too(cfg):
    sc = stage_config(canonical(stage_slice(cfg, "model")))
    for use in (lambda v: v == "branch", lambda v: f"{v}", lambda v: f"{v:g}", lambda v: str(v), lambda v: -v):
        with pytest.raises(CapmapError, match="config field planning is not in this stage's slice"):
            use(sc.run.planning)


def test_an_absent_section_comes_back_as_none_and_the_atlas_start_is_resolved(doc):
    d = copy.deepcopy(doc)
    for section in ("reconfig", "dualarm", "follow"):
        d.pop(section)
    d["task"].pop("start_m")  # the start is then FK(q_ini): the atlas maps read the resolved one
    c = check_run_config(d)
    for stage in ("reconfig_nullspace", "dualarm_optimise"):
        sc = stage_config(canonical(stage_slice(c, stage)))
        assert sc.run.reconfig is None if stage.startswith("reconfig") else sc.run.dualarm is None
    atlas = stage_config(canonical(stage_slice(c, "atlas_map"))).run
    assert atlas.failure.start_m == pytest.approx(c.failure.start_m, abs=1e-9) and None not in atlas.failure.start_m
