"""The failure in one edit (issue 25, item 5): each of the README's lock examples, applied alone to
config/config.yaml (its further tasks kept), passes the checks and runs the capacity map with its
plans, verifications and the further tasks end to end at a small size (the size keys are the only
other change: a tiny map)."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
import yaml

from capmap.checks import check_run_config
from capmap.config.run import run_document
from capmap.robots import load, locked_arm
from tests.scenario import ROOT
from tests.workflow.runs import snakemake

pytestmark = pytest.mark.slow  # a whole tiny pipeline: .ci/run runs these (-m slow)

SMALL = {"sampling": {"mode": "voxel_fill", "n_points": 300, "jitter_per_voxel": 0, "seed": 7},
         "directions": {"kind": "sphere", "n": 12}, "voxels": {"edge_m": 3.0, "refine": False},
         "planning": {"gain_tasks": 2}, "shards": 2}


def readme_lock_examples() -> list[dict]:
    """The ``lock:`` blocks of the README's section "The failure in one edit"."""
    text = (ROOT / "docs" / "capacity-map.md").read_text()
    section = text.split("## The failure in one edit", 1)[1].split("\n## ", 1)[0]
    blocks = [yaml.safe_load(b) for b in re.findall(r"```yaml\n(.*?)```", section, re.S)]
    return [b for b in blocks if isinstance(b, dict) and set(b) == {"lock"}]


def _edited(example: dict) -> dict:
    doc = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    doc.update(example)
    return doc


def test_the_readme_has_one_edit_examples():
    examples = readme_lock_examples()
    assert len(examples) >= 2 and {e["lock"]["joint"] for e in examples} >= {1, 3}


@pytest.mark.parametrize("example", readme_lock_examples(), ids=lambda e: repr(e["lock"]))
def test_a_lock_edit_alone_keeps_every_task_valid(example):
    doc = _edited(example)
    assert doc["tasks"], "the default config's further tasks are kept"
    cfg = check_run_config(run_document([], {k: doc[k] for k in ("lock", "tasks")}))
    assert cfg.failure.joint == example["lock"]["joint"]
    arm = locked_arm(load(cfg.robot), cfg.failure.joint, cfg.failure.angle_deg)
    for t in cfg.tasks:  # each further task starts on an exact IK solution of the edited lock (Pinocchio's FK)
        assert t.q_start_deg[cfg.failure.joint - 1] == cfg.failure.angle_deg
        q = np.deg2rad(np.delete(np.asarray(t.q_start_deg), cfg.failure.joint - 1))
        data = arm.reduced_model.createData()
        pin.framesForwardKinematics(arm.reduced_model, data, q)
        assert np.linalg.norm(data.oMf[arm.reduced_ee_frame_id].translation - t.start_m) < 1e-8


@pytest.mark.parametrize("example", readme_lock_examples(), ids=lambda e: repr(e["lock"]))
def test_a_lock_edit_alone_runs_end_to_end(example, tmp_path):
    doc = _edited(example) | SMALL
    doc["run"] = "one_edit"
    for key in ("follow", "reconfig", "dualarm", "atlas"):  # other families: not what the edit changes
        doc.pop(key, None)
    doc["robot"] = str(ROOT / doc["robot"])
    cfg = tmp_path / "one_edit.yaml"
    cfg.write_text(yaml.safe_dump(doc))
    res = snakemake(tmp_path, cfg, "capacity_map", timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    for t in doc["tasks"]:
        assert (tmp_path / f"results/one_edit/tasks/{t['name']}/workspace.png").stat().st_size > 0
