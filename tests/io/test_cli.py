"""``python -m capmap check-config``: a config file read and checked by capmap's own loader, as the
workflow does before any job (Snakemake itself reads a --configfile first)."""

import subprocess
import sys

from tests.scenario import ROOT


def _cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "capmap", *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_the_default_config_is_valid_and_its_failure_described():
    res = _cli("check-config")
    assert res.returncode == 0, res.stderr
    assert "config/config.yaml: valid; run 'default'; joint 1 locked at 100 deg" in res.stdout


def test_a_template_or_a_bad_key_is_one_line(tmp_path):
    yte = tmp_path / "yte.yaml"
    yte.write_text((ROOT / "config" / "config.yaml").read_text() + "\n__use_yte__: true\n")
    typo = tmp_path / "typo.yaml"
    typo.write_text((ROOT / "config" / "config.yaml").read_text().replace("limits:", "limts:"))
    for path, expect in ((yte, "capmap does not evaluate YTE templates"), (typo, "unknown key limts")):
        res = _cli("check-config", str(path))
        lines = res.stderr.splitlines()
        assert res.returncode == 1 and len(lines) == 1 and expect in lines[0] and str(path) in lines[0], res.stderr


def test_arm_prints_each_lock_classification():
    """The SSRMS: joints 1, 2, 6, 7 locked -> closed forms, 3, 4, 5 -> the search; the Panda with joint 2
    at mid-range (0 deg: joints 1 and 3 on one line) is flagged as a continuum."""
    out = _cli("arm", "config/robots/ssrms7.yaml")
    assert out.returncode == 0, out.stderr
    lines = [ln for ln in out.stdout.splitlines() if "locked at" in ln]
    assert len(lines) == 7
    assert all("closed_form" in lines[j - 1] for j in (1, 2, 6, 7))
    assert all("semi_analytic" in lines[j - 1] for j in (3, 4, 5))
    out = _cli("arm", "config/robots/panda.yaml")
    assert out.returncode == 0, out.stderr
    lines = [ln for ln in out.stdout.splitlines() if "locked at" in ln]
    assert "COLLINEAR" in lines[1] and "may miss branches" in lines[1]
    assert all("general_6r (complete)" in lines[j - 1] for j in (1, 3, 4, 5, 6, 7))
