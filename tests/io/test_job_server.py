"""The job server (capmap.io.logs.call with a named function, capmap.io.job_server): a job's function runs
in a child of the server, in the job's folder and environment, its stderr the job's and its exit status the
job's; without a server the job runs it; a job that goes away ends its child."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from capmap.io import job_server
from capmap.io.job_client import ENV

ROOT = Path(__file__).resolve().parents[2]
TARGETS = "tests.io.job_targets"


@pytest.fixture
def server(monkeypatch):
    monkeypatch.setenv("PYTHONPATH", f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}")
    srv = job_server.start([TARGETS])
    t = time.monotonic()
    while not os.path.exists(srv.path):
        assert time.monotonic() - t < 60 and srv.process.poll() is None, "the server did not start"
        time.sleep(0.05)
    yield srv
    srv.stop()
    assert not os.path.exists(os.path.dirname(srv.path))  # its private folder removed


def _job(target: str, cwd: Path, socket_path: str | None, capture: bool = True, **kwargs) -> subprocess.Popen:
    """A job's script: ``call("tests.io.job_targets:<target>", **kwargs)`` in a new process (its stdout and
    stderr to pipes, or with ``capture=False`` to nowhere: a child holding them open would keep a pipe
    open after the job has gone)."""
    env = dict(os.environ, CAPMAP_TEST_VALUE="from the job", PYTHONPATH=str(ROOT))
    env.pop(ENV, None)
    if socket_path:
        env[ENV] = socket_path
    code = f"from capmap.io.logs import call\ncall({f'{TARGETS}:{target}'!r}, **{kwargs!r})"
    out = subprocess.PIPE if capture else subprocess.DEVNULL
    return subprocess.Popen([sys.executable, "-c", code], cwd=cwd, env=env, stdout=out, stderr=out, text=True)


def _ran(out: Path) -> tuple[str, str, int, int]:
    cwd, value, pid, ppid = out.read_text().split("\n")[:4]
    return cwd, value, int(pid), int(ppid)


def test_a_named_function_runs_in_a_child_of_the_server_as_the_job(server, tmp_path):
    job = _job("report", tmp_path, server.path, out="ran.txt")
    _, err = job.communicate(timeout=60)
    assert job.returncode == 0, err
    cwd, value, pid, ppid = _ran(tmp_path / "ran.txt")
    assert (cwd, value) == (str(tmp_path), "from the job")  # the job's folder and environment
    assert ppid == server.process.pid and pid != job.pid  # run by the server's child, not the job
    assert "a line to the job's stderr" in err  # the job's own stderr


def test_the_childs_failure_is_the_jobs_one_line_and_exit_status(server, tmp_path):
    job = _job("fail", tmp_path, server.path)
    _, err = job.communicate(timeout=60)
    assert job.returncode == 1
    assert "a planted failure" in err and "Traceback" not in err


@pytest.mark.parametrize("where", ["no server named", "a server gone"])
def test_without_a_server_the_job_runs_the_function_itself(tmp_path, where):
    path = None if where == "no server named" else str(tmp_path / "gone" / "socket")
    job = _job("report", tmp_path, path, out="ran.txt")
    _, err = job.communicate(timeout=60)
    assert job.returncode == 0, err
    assert _ran(tmp_path / "ran.txt")[2] == job.pid


def test_a_job_that_goes_away_ends_its_child(server, tmp_path):
    job = _job("wait", tmp_path, server.path, capture=False, out="pid.txt")
    t = time.monotonic()
    while not (tmp_path / "pid.txt").exists() or not (tmp_path / "pid.txt").read_text():
        assert time.monotonic() - t < 60, "the child did not start"
        time.sleep(0.05)
    child = int((tmp_path / "pid.txt").read_text())
    job.kill()
    job.wait()
    t = time.monotonic()
    while _alive(child):
        assert time.monotonic() - t < 10, "the child runs on after its job went away"
        time.sleep(0.05)


def test_the_server_listens_before_its_imports_are_done_and_skips_one_that_fails(monkeypatch, tmp_path):
    """Its imports come after it listens (a module whose import waits for this test's go), one that fails
    (no such module) is skipped, and the children forked after an import inherit it."""
    monkeypatch.setenv("PYTHONPATH", f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}")
    go = tmp_path / "go"
    monkeypatch.setenv("CAPMAP_TEST_GO", str(go))
    srv = job_server.start(["capmap.no_such_module", TARGETS, "tests.io.slow_import"])
    try:
        t = time.monotonic()
        while not os.path.exists(srv.path):  # a server importing first would listen only after 120 s
            assert time.monotonic() - t < 60 and srv.process.poll() is None, "the server does not listen"
            time.sleep(0.05)
        go.touch()
        t = time.monotonic()
        while True:  # the import is done, and inherited, once a child sees it
            job = _job("modules", tmp_path, srv.path, out="modules.txt")
            _, err = job.communicate(timeout=60)
            assert job.returncode == 0, err
            if (tmp_path / "modules.txt").read_text() == "True":
                break
            assert time.monotonic() - t < 60, "no child of the server has the slow module imported"
            time.sleep(0.1)
        job = _job("report", tmp_path, srv.path, out="ran.txt")
        _, err = job.communicate(timeout=60)
        assert job.returncode == 0, err
        assert _ran(tmp_path / "ran.txt")[3] == srv.process.pid  # served after the failed import
    finally:
        srv.stop()


def test_the_server_ends_with_the_process_that_started_it(tmp_path):
    code = (f"import sys; sys.path.insert(0, {str(ROOT)!r}); from capmap.io import job_server; "
            f"print(job_server.start([{TARGETS!r}]).process.pid, flush=True)")
    starter = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    pid = int(starter.stdout)
    t = time.monotonic()
    while _alive(pid):
        assert time.monotonic() - t < 30, "the server runs on after its workflow ended"
        time.sleep(0.1)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie of this process counts as ended
        return os.waitpid(pid, os.WNOHANG) == (0, 0)
    except ChildProcessError:
        return _state(pid) != "Z"


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(")")[1].split()[0]
    except OSError:
        return "Z"


def test_a_malformed_or_broken_request_does_not_stop_the_server(server, tmp_path):
    import socket

    for payload in (b"", b"\x00\x00\x00\x05{not", b"\x00\x00\x01\x00" + b"x" * 20):
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.connect(server.path)
        if payload:
            s.sendall(payload)
        s.close()
    job = _job("report", tmp_path, server.path, out="ran.txt")
    _, err = job.communicate(timeout=60)
    assert job.returncode == 0, err
    assert _ran(tmp_path / "ran.txt")[3] == server.process.pid  # still served


def test_the_server_imports_the_stage_modules_the_scripts_name_the_dual_arm_ones_only_with_that_family():
    scripts = ROOT / "workflow" / "scripts"
    every, without = job_server.stage_modules(scripts, True), job_server.stage_modules(scripts, False)
    assert {"capmap.stages.refine", "capmap.stages.dualarm_solve"} <= set(every)
    assert "capmap.stages.refine" in without and not any("dualarm" in m for m in without)
    assert all(m.startswith("capmap.stages.") for m in every)
