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


# --- usage errors: one line, exit status 1 (argparse's own is 2 and a usage block) ---------------------------------

def _one_line(res, *expect):
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert res.returncode == 1 and len(lines) == 1 and lines[0].startswith("capmap:"), res.stderr
    assert "Traceback" not in res.stderr + res.stdout
    for text in expect:
        assert text in lines[0], lines[0]
    return lines[0]


import pytest  # noqa: E402


@pytest.mark.parametrize("args, expect", [
    (("query", "point", "abc", "0", "1"), "argument x: 'abc' is not a number"),
    (("query", "point", "nan", "0", "1"), "'nan' is not a finite number"),
    (("query", "point", "1", "2"), "the following arguments are required: z"),
    (("query", "line", "0", "0", "0", "1", "1", "inf"), "argument bz: 'inf' is not a finite number"),
    (("query", "point", "1", "2", "3", "--payload=-inf"), "is not a finite number"),
    (("query", "point", "1", "2", "3", "--payload", "-1"), "--payload -1.0 must be a finite mass >= 0 kg"),
    (("frobnicate",), "invalid choice: 'frobnicate'"),
    (("catalogue", "no-such-run"), "no catalogue.parquet"),
    (("arm", "config/robots/ssrms7.yaml", "--angle-deg", "nan"), "'nan' is not a finite number"),
    (("check-config", "--json", "no/such.yaml"), "no/such.yaml"),
    (("run", "--cores"), "expected one argument"),
])
def test_a_usage_error_is_one_line(args, expect):
    _one_line(_cli(*args), expect)


@pytest.mark.parametrize("args", [("--help",), ("query", "point", "--help"), ("query", "line", "--help"),
                                  ("run", "--help"), ("check", "--help"), ("check-config", "--help"),
                                  ("catalogue", "--help"), ("arm", "--help")])
def test_help_is_printed(args):
    res = _cli(*args)
    assert res.returncode == 0 and res.stdout.startswith("usage: capmap") and not res.stderr, res.stderr


def test_a_line_beyond_the_pipeline_bounds_is_refused_before_any_allocation():
    """A line to a point 1000 km away: the pipeline's bound on a verified line's duration, one line."""
    res = _cli("query", "line", "0.379", "4.8432", "1.8878", "1e6", "0", "0", "--configfile", "tests/data/tiny.yaml")
    _one_line(res, "task.v_max_mps, task.a_max_mps2: the queried line (1e+06 m) would take")


# --- `capmap run`: capmap's loader reads the config before Snakemake is started ------------------------------------

def _special(tmp_path, kind):
    import os

    path = tmp_path / f"{kind}.yaml"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "folder":
        path.mkdir()
    elif kind == "deep":
        path.write_text("a: " + "[" * 5000 + "]" * 5000 + "\n")
    elif kind == "yte":
        text = (ROOT / "config" / "config.yaml").read_text()
        path.write_text("__use_yte__: true\n" + text.replace("run: default", f"run: ?__import__('os').system("
                                                                             f"'touch {tmp_path}/pwned')"))
    return str(path)


@pytest.mark.parametrize("kind, expect", [("fifo", "is a FIFO"), ("folder", "is a directory"),
                                          ("deep", "nested deeper than"), ("yte", "capmap does not evaluate YTE"),
                                          ("missing", "no such file")])
def test_run_refuses_a_config_before_snakemake_reads_it(tmp_path, kind, expect):
    """A FIFO (Snakemake's reader would wait on it), a folder, a deep file, a YTE template (Snakemake would run its
    Python), a missing file: one line, nothing run, no Snakemake started."""
    res = _cli("run", _special(tmp_path, kind), "-n")
    _one_line(res, expect)
    assert not (tmp_path / "pwned").exists() and "snakemake" not in res.stderr.split(":", 2)[-1].split("(")[0]


def test_run_hands_a_checked_config_to_snakemake_by_name(tmp_path):
    """A good config: checked, then `snakemake --config configfile=<it>` (a dry run here): the run is named after
    the file as with --configfile."""
    cfg = tmp_path / "mytiny.yaml"
    text = (ROOT / "tests" / "data" / "tiny.yaml").read_text()
    cfg.write_text(text.replace("config/robots/", f"{ROOT}/config/robots/").replace("config/scenes/",
                                                                                    f"{ROOT}/config/scenes/"))
    res = _cli("run", str(cfg), "capacity_map", "-n", cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-2000:]
    assert f"--config configfile={cfg}" in res.stderr and "results/" in res.stderr


def test_config_named_twice_is_one_line(tmp_path):
    res = subprocess.run(["snakemake", "-n", "-s", str(ROOT / "Snakefile"), "-d", str(tmp_path), "--cores", "1",
                          "--configfile", str(ROOT / "tests" / "data" / "tiny.yaml"),
                          "--config", f"configfile={ROOT / 'config' / 'config.yaml'}"],
                         capture_output=True, text=True, timeout=300)
    line = [ln for ln in res.stderr.splitlines() if ln.startswith("capmap:")]
    assert res.returncode == 1 and len(line) == 1 and "give the run's config one way" in line[0], res.stderr[-1500:]


def test_json_answers_parse():
    """--json on the commands that answer without a run: one JSON document on stdout."""
    import json

    res = _cli("check-config", "--json", "tests/data/tiny.yaml")
    assert res.returncode == 0 and json.loads(res.stdout)["valid"] is True, res.stderr
    res = _cli("arm", "config/robots/ssrms7.yaml", "--json")
    doc = json.loads(res.stdout)
    assert res.returncode == 0 and len(doc["joints"]) == 7 and len(doc["locks"]) >= 7


def test_capmap_run_shows_one_line_per_job_and_the_job_table_in_one(capfd):
    """Snakemake's scheduling lines and step counts are left out, each job's capmap line and the rest kept."""
    from capmap.__main__ import _snakemake

    lines = ["Building DAG of jobs...", "Job stats:", "job      count", "-----  -------", "capacity       4",
             "voxels         1", "all            1", "total          6", "Select jobs to execute...", "Execute 2 jobs...",
             "[12:00:01] capacity shard 0 of 4: done (1.6 s, 394 MB)", "[Sun Dec  6 05:10:58 2026]",
             "Finished jobid: 3 (Rule: capacity)", "1 of 6 steps (17%) done", "capmap: what this run found:"]
    assert _snakemake(["printf", "%s\\n", *lines]) == 0
    err = capfd.readouterr().err.splitlines()
    assert err == ["capmap: 6 jobs to run: capacity x4, voxels", "[12:00:01] capacity shard 0 of 4: done (1.6 s, 394 MB)",
                   "capmap: what this run found:"]
