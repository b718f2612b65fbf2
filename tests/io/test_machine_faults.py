"""Faults of the machine: a full disk, a read-only or unusable results folder, no memory left. The job fails
(it cannot do its work), with one ``capmap:`` line, and leaves no half-written file; a results folder that
cannot be written is known before any job."""

from __future__ import annotations

import errno
import os
import subprocess

import pandas as pd
import pytest

from capmap.errors import CapmapError
from capmap.io import datasets
from capmap.io.logs import call
from capmap.io.runs import check_writable
from tests.scenario import ROOT
from tests.workflow.runs import config_file


def _full_disk(self, path, *args, **kwargs):
    """DataFrame.to_parquet on a full disk: a part of the file written, then ENOSPC."""
    with open(path, "wb") as f:
        f.write(b"PAR1 half a file")
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))


def _stage_writing(out: str) -> None:
    datasets.write(pd.DataFrame({"x_m": [1.0, 2.0]}), out, datasets.provenance("test", {}))


def test_a_full_disk_is_one_line_and_leaves_no_temp_file(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(pd.DataFrame, "to_parquet", _full_disk)
    out = tmp_path / "voxels" / "voxels.parquet"
    with pytest.raises(SystemExit) as info:
        call(_stage_writing, log=str(tmp_path / "job.log"), out=str(out))
    assert info.value.code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("capmap: cannot write") and "No space left on device" in err[0], err
    assert "voxels.tmp.parquet" in err[0]  # the file it could not write, named
    assert sorted(p.name for p in out.parent.iterdir()) == []  # neither the output nor its temp file


def test_a_bug_is_still_a_traceback(tmp_path):
    """Not every OSError is the machine's: a wrong argument (a bug) keeps its traceback."""
    def buggy(out: str) -> None:
        raise OSError(errno.EINVAL, "Invalid argument")

    with pytest.raises(OSError):
        call(buggy, out=str(tmp_path / "x"))


@pytest.mark.parametrize("make", ["file_in_the_way", "under_a_file"])
def test_a_results_folder_that_cannot_be_written_is_one_line(tmp_path, make):
    """Root writes anywhere: a folder that cannot be made (a file in its way) stands for a read-only one."""
    blocker = tmp_path / "results"
    blocker.write_text("not a folder")
    run_dir = blocker if make == "file_in_the_way" else blocker / "tiny"
    with pytest.raises(CapmapError, match="the run's outputs cannot be written there"):
        check_writable(run_dir)
    check_writable(tmp_path / "ok" / "tiny")  # a folder that can be made: made, nothing left in it
    assert list((tmp_path / "ok" / "tiny").iterdir()) == []


def test_snakemake_refuses_an_unwritable_results_folder_before_any_job(tmp_path):
    cfg = config_file(tmp_path)
    (tmp_path / "results").write_text("a file where the results folder goes")
    res = subprocess.run(["snakemake", "-n", "all", "-s", str(ROOT / "Snakefile"), "-d", str(tmp_path), "--cores", "1",
                          "--config", f"configfile={cfg}"],
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("capmap:")]
    assert res.returncode == 1 and any("cannot be written there" in ln for ln in lines), res.stderr[-2000:]
    assert "Traceback" not in res.stderr


_ORPHAN = """
import os, sys, time, subprocess
child = subprocess.Popen([sys.executable, "-c", '''
import time, pathlib
from capmap.io.logs import call
def job(out):
    pathlib.Path(out).write_text("started")
    try:
        while True:
            time.sleep(0.05)
    finally:
        pathlib.Path(out + ".cleaned").write_text("yes")
call(job, out=r"{out}")
'''])
print(child.pid, flush=True)
time.sleep(60)
"""


def test_a_job_ends_when_the_workflow_that_started_it_is_killed(tmp_path):
    """Snakemake killed outright (SIGKILL: no chance to end its jobs): the job notices its parent is gone, ends
    within seconds, and runs its clean-up (``finally``) on the way out."""
    import signal
    import sys
    import time

    out = tmp_path / "job.txt"
    parent = subprocess.Popen([sys.executable, "-c", _ORPHAN.replace("{out}", str(out))], stdout=subprocess.PIPE,
                              text=True)
    child = int(parent.stdout.readline())
    for _ in range(200):  # the job is running
        if out.exists():
            break
        time.sleep(0.05)
    assert out.read_text() == "started"
    parent.kill()
    parent.wait()
    for _ in range(100):  # gone within 5 s (the watcher polls each second)
        try:
            os.kill(child, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        os.kill(child, signal.SIGKILL)
        pytest.fail("the job ran on after its workflow was killed")
    assert (tmp_path / "job.txt.cleaned").read_text() == "yes"
