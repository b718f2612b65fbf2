"""Platform robot files and their models: against a hand-written FK; bad files are one line."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from capmap.errors import ConfigError
from capmap.reconfig.multiarm import arm_elements, chain_of, platform_model
from capmap.reconfig.platform_file import load_platform
from capmap.robots import load
from tests.reconfig.conftest import CAPTURE_DEG, RECONFIG_YAML, state_of
from tests.reference.platform_fk import link_poses


def test_reference_geometry_and_capture_closure(platform):
    """The spec's capture configuration closes the capture within its 4-decimal rounding."""
    poses = link_poses(RECONFIG_YAML, CAPTURE_DEG)
    rel = np.linalg.inv(poses["arm2.ee"]) @ poses["arm1.ee"]
    assert np.allclose(rel[:3, 3], 0, atol=5e-6)
    assert np.allclose(rel[:3, :3], np.diag([1.0, -1.0, -1.0]), atol=5e-6)  # Rx(180 deg): tool z axes opposed
    assert [a.name for a in platform.arms] == ["arm1", "arm2", "arm3"] and len(platform.captures) == 3


def test_pinocchio_model_and_chains_match_hand_written_fk(platform):
    rng = np.random.default_rng(0)
    model = platform_model(platform)
    for _ in range(5):
        q_deg = {a.name: rng.uniform(-180, 180, 6).tolist() for a in platform.arms}
        passive = {f"{a.name}.{p}": (rng.uniform(-90, 90), rng.uniform(-0.5, 0.8)) for a in platform.arms
                   for p in ("P1", "P2")}
        expect = link_poses(RECONFIG_YAML, q_deg, passive)
        state = state_of(platform, q_deg)
        for name, (th, d) in passive.items():
            state = state.with_passive(name, np.deg2rad(th), d)
        got = model.placements(state, tuple(expect))
        for (name, T), G in zip(expect.items(), got):
            assert np.allclose(G, T, atol=1e-12), name
        for arm in platform.arms:  # the element chains (passive joints locked at their state) agree too
            chain, names = chain_of(arm_elements(arm, f"{arm.name}.ee", state))
            T = chain.fk(np.array([[state.q[n] for n in names]]))[0]
            assert np.allclose(T, expect[f"{arm.name}.ee"], atol=1e-12)


def _bad(tmp_path, mutate):
    doc = yaml.safe_load(RECONFIG_YAML.read_text())
    mutate(doc)
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(doc))
    with pytest.raises(ConfigError) as exc:
        load_platform(p)
    msg = str(exc.value)
    assert "\n" not in msg and str(p) in msg
    return msg


def _joint(doc, arm, k):
    doc["arms"][arm]["joints"] = [dict(j) for j in doc["arms"][arm]["joints"]]  # undo the shared anchor
    return doc["arms"][arm]["joints"][k]


@pytest.mark.parametrize("mutate, expect", [
    (lambda d: _joint(d, 0, 2).pop("axis"), "arms[0].joints[2] (arm1.P1): a passive cylindrical joint needs an axis"),
    (lambda d: _joint(d, 1, 4).update(range_m=[0.8, -0.5]), "arms[1].joints[4].range_m = [0.8, -0.5] (arm2.P2): "
                                                            "the extension range is inverted"),
    (lambda d: d["arms"][2].update(name="arm1"), "arms[2].name = 'arm1': two arms have the same name"),
    (lambda d: d["captures"][0].update(link_b="arm9.ee"), "captures[0].link_b = 'arm9.ee' is not a link"),
    (lambda d: d["captures"][1].update(link_a="arm1.J7"), "captures[1].link_a = 'arm1.J7' is not a link"),
    (lambda d: _joint(d, 0, 0).update(type="prismatic"), "arms[0].joints[0].type"),
    (lambda d: _joint(d, 0, 3).update(range_deg=[90, -90]), "arms[0].joints[3].range_deg = [90, -90] (arm1.J3)"),
    (lambda d: _joint(d, 0, 2).update(axis=[0, 0, 0]), "arms[0].joints[2].axis = [0, 0, 0] (arm1.P1) must not be zero"),
    (lambda d: d["captures"].append(dict(d["captures"][0])), "captures[3].name = 'arm1_arm2': two captures"),
    (lambda d: d["captures"][0].update(link_b="arm1.J2"), "captures[0] holds two links of the same arm"),
    (lambda d: d["arms"][0].update(speed=1), "unknown key arms[0].speed"),
])
def test_bad_platform_files_are_one_line(tmp_path, mutate, expect):
    assert expect in _bad(tmp_path, mutate)


def test_platform_file_is_not_a_single_arm(tmp_path):
    with pytest.raises(ConfigError, match="describes a platform of arms"):
        load(RECONFIG_YAML)
