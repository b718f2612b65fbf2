"""Robot files: every bad file is one line naming the field."""

import pytest
import yaml

from capmap.errors import CapmapError, ConfigError
from capmap.robots import load, load_robot
from tests.scenario import SSRMS_YAML


def _bad(tmp_path, mutate, text=None):
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    if mutate:
        mutate(doc)
    p = tmp_path / "bad.yaml"
    p.write_text(text if text is not None else yaml.safe_dump(doc))
    with pytest.raises(CapmapError) as exc:
        load(p)
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_bad_robot_files_name_the_field(tmp_path):
    assert "links[2].mass_kg" in _bad(tmp_path, lambda d: d["links"][2].update(mass_kg=-1.0))
    assert "links[0].inertia_kgm2" in _bad(tmp_path, lambda d: d["links"][0].update(inertia_kgm2=[1.0, -1.0, 1.0]))
    assert "triangle" in _bad(tmp_path, lambda d: d["links"][0].update(inertia_kgm2=[0.1, 0.1, 5.0]))
    assert "not positive definite" in _bad(
        tmp_path, lambda d: d["links"][0].update(inertia_kgm2=[1.0, 1.0, 1.0, 2.0, 0.0, 0.0]))
    assert "dh.rows[3]" in _bad(tmp_path, lambda d: d["dh"]["rows"][3].append(1.0))
    assert "dh.convention" in _bad(tmp_path, lambda d: d["dh"].update(convention="craig"))
    assert "masss_kg" in _bad(tmp_path, lambda d: d["links"][1].update(masss_kg=3.0))
    assert "gravity" in _bad(tmp_path, lambda d: d.update(gravity=[0, 0, 0]))
    assert "links has 6" in _bad(tmp_path, lambda d: d["links"].pop())
    assert "joint_range_deg[1]" in _bad(tmp_path, lambda d: d["joint_range_deg"].__setitem__(1, [10, -10]))
    assert "malformed YAML" in _bad(tmp_path, None, text="name: x\ndh: [1, 2\n")
    assert "urdf.path" in _bad(tmp_path, None, text="name: x\nurdf: {path: nope.urdf, ee_frame: tool}\n")


def test_missing_file_is_one_line(tmp_path):
    with pytest.raises(CapmapError, match="cannot read"):
        load_robot(tmp_path / "absent.yaml")


def test_errors_are_config_errors(tmp_path):
    (tmp_path / "r.yaml").write_text("name: x\nurdf: {path: nope.urdf, ee_frame: tool}\n")
    with pytest.raises(ConfigError):
        load(tmp_path / "r.yaml")
