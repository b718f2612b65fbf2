import numpy as np
import pytest
import yaml

from capmap.capacity.build import load_limits, task_rotation
from capmap.checks import check_run_config
from capmap.config import load_config, parse_config
from capmap.errors import CapmapError
from tests.scenario import ROOT, TASK_R


def _doc():
    return yaml.safe_load((ROOT / "config" / "config.yaml").read_text())


def test_default_config_parses_to_the_spec_scenario():
    run = load_config(ROOT / "config" / "config.yaml")
    assert run.lock.joint == 1 and run.lock.angle_deg is None  # locked where it stood
    assert check_run_config(_doc()).failure.angle_deg == 100
    assert np.allclose(task_rotation(run.task), TASK_R, atol=1e-15)  # independent Rz Ry Rx in tests/scenario.py
    limits = load_limits(run.limits, 7)
    assert np.all(limits.joint_torque_nm == 700) and np.all(limits.base_moment_nm == 500)


@pytest.mark.parametrize("mutate, expect", [
    (lambda d: d["task"].update(v_max_mps=0), "task.v_max_mps"),
    (lambda d: d["sampling"].update(mode="grid"), "sampling.mode"),
    (lambda d: d["directions"].update(kind="sphere"), "directions.n is required"),
    (lambda d: d.update(shards=0), "shards"),
    (lambda d: d["lock"].update(joint="one"), "lock.joint"),
])
def test_config_errors_name_the_key(mutate, expect):
    doc = _doc()
    mutate(doc)
    with pytest.raises(CapmapError, match=expect.replace(".", r"\.")):
        parse_config(doc)


@pytest.mark.parametrize("period, store, every", [(0.001, None, 10), (0.02, None, 1), (0.004, None, 2),
                                                  (0.003, 0.01, 3), (0.001, 0.001, 1)])
def test_the_stored_series_period_defaults_to_a_valid_one_and_never_stores_coarser_than_asked(period, store, every):
    """A control period above the default store period is a valid config without the key (the default
    follows it); rows are never farther apart than asked (a whole number of control periods)."""
    doc = _doc()
    doc["follow"]["period_s"] = period
    if store is not None:
        doc["follow"]["store_period_s"] = store
    fol = check_run_config(doc).follow
    assert fol.store_every == every
    assert fol.store_every * period <= max(store or 0.01, period) * (1 + 1e-9)
