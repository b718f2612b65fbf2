"""Warm jobs: a local run's stage functions run in children of one process that has imported them.

A Snakemake job is a new Python process; before its work it imports numpy, pandas, Pinocchio, numba and
capmap and loads the compiled kernels it calls, about a second per job, as long as many of the default
run's jobs take. The run's ``onstart`` starts this server (:func:`start`, local runs only): it listens at
once on a Unix socket in a private temporary folder, named to the jobs by :data:`ENV`, and between jobs
imports what every stage imports (:data:`BASE`), then the stage modules, then loads the run's kernels, one
at a time, so that the first jobs are served too (a child imports what the server has not yet). A job's
script (:func:`capmap.io.logs.call` with a
``"module:function"`` target) sends the function's name, its arguments (plain JSON: paths, numbers, the
slice), the job's working folder and environment and its stdout and stderr themselves (the file
descriptors); the server forks and the child runs the function there as the script would have (the same
logging, one-line errors and log file), and its exit status goes back to the script, which exits with it.

No server (a cluster run, a script run by hand, the server not yet listening, or gone): the script runs the
function itself. A job that Snakemake ends (its script's process gone) ends its child; the server and its
children end with the workflow's process.
"""

from __future__ import annotations

import importlib
import json
import os
import selectors
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from capmap.io.fingerprint import script_modules
from capmap.io.job_client import CODE, LEN, recv
from capmap.io.logs import call, named

__all__ = ["JobServer", "BASE", "stage_modules", "start", "serve"]

BASE = ("numpy", "pandas", "pyarrow.parquet", "scipy.linalg", "numba", "pinocchio")
"""What every stage imports: the server imports these first."""


@dataclass(frozen=True)
class JobServer:
    """A started server: its socket's path and its process."""

    path: str
    process: subprocess.Popen

    def stop(self) -> None:
        """End the server (its children end with it) and wait for it."""
        if self.process.poll() is None:
            self.process.terminate()
        self.process.wait()


def stage_modules(scripts: Path, dualarm: bool) -> list[str]:
    """The stage modules the workflow's scripts (``scripts``: their folder) name, the dual-arm family's only
    when the run has it: what a run's server imports."""
    return sorted({m for f in Path(scripts).glob("*.py") for m in script_modules(f)
                   if m.startswith("capmap.stages.") and (dualarm or "dualarm" not in m)})


def start(modules: list[str], warm: tuple[str, dict] | None = None) -> JobServer:
    """Start a server as a child of this process (it ends when this process does) that imports :data:`BASE`
    and ``modules`` and calls ``warm`` (a function's ``"module:function"`` name and its keyword arguments:
    the run's kernels loaded, :func:`capmap.kernels.warm`) between the jobs it serves. Returns at once:
    until the server listens (a fraction of a second), jobs run their functions themselves."""
    folder = tempfile.mkdtemp(prefix="capmap-jobs-")  # mode 0700: the socket is this user's
    path = os.path.join(folder, "socket")
    cmd = [sys.executable, "-m", "capmap.io.job_server", path, str(os.getpid()), *modules]
    if warm:
        cmd += ["--warm", warm[0], json.dumps(warm[1])]
    with open(os.path.join(folder, "server.log"), "w") as log:
        # in its own folder: the run's folder is not held by it (it may outlive Snakemake by a moment)
        proc = subprocess.Popen(cmd, cwd=folder, stdin=subprocess.DEVNULL, stdout=log, stderr=log, start_new_session=True)
    return JobServer(path, proc)


def _child(request: dict, fds: list[int], inherited: list[socket.socket]) -> None:
    """In the forked child: the server's sockets closed, become the job (its stdout, stderr, folder,
    environment), run it, exit."""
    code = 1
    try:
        for s in inherited:
            s.close()
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.set_wakeup_fd(-1)
        for fd, target in zip(fds, (1, 2)):
            os.dup2(fd, target)
            os.close(fd)
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        call(named(request["target"]), **request["kwargs"])
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except BaseException:
        traceback.print_exc()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def serve(path: str, parent: int, pending: Sequence[Callable[[], object]] = ()) -> None:
    """Accept jobs on ``path`` until process ``parent`` is gone: per job a forked child (:func:`_child`);
    a job's socket closed before its child ends ends the child (SIGTERM); each child's exit status is
    sent back as it ends. ``pending``: calls made one at a time while no job is waiting (imports, the
    kernels' loading: the children forked after one inherit what it did); one that fails is logged and
    skipped (a child then meets the failure in its own job). One thread: forking is safe."""
    pending = list(pending)
    wake_r, wake_w = socket.socketpair()
    wake_r.setblocking(False)
    wake_w.setblocking(False)
    signal.signal(signal.SIGCHLD, lambda *_: None)
    signal.set_wakeup_fd(wake_w.fileno())
    srv = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    srv.bind(path)
    srv.listen(64)
    sel = selectors.DefaultSelector()
    sel.register(srv, selectors.EVENT_READ)
    sel.register(wake_r, selectors.EVENT_READ)
    jobs: dict[socket.socket, int] = {}
    try:
        while os.getppid() == parent:
            for key, _ in sel.select(timeout=0.0 if pending else 0.5):
                if key.fileobj is srv:
                    conn, _ = srv.accept()
                    got = _request(conn)
                    if got is None:
                        conn.close()
                        continue
                    sys.stdout.flush()
                    sys.stderr.flush()
                    pid = os.fork()
                    if pid == 0:
                        _child(got[0], got[1], [srv, wake_r, wake_w, conn, *jobs])
                    for fd in got[1]:
                        os.close(fd)
                    jobs[conn] = pid
                    sel.register(conn, selectors.EVENT_READ)
                elif key.fileobj is wake_r:
                    while True:
                        try:
                            if not wake_r.recv(512):
                                break
                        except BlockingIOError:
                            break
                else:  # a job's socket readable: its script went away (it sends nothing more): end its child
                    sel.unregister(key.fileobj)
                    _kill(jobs[key.fileobj])
            _reap(jobs, sel)
            if pending:
                try:
                    pending.pop(0)()
                except Exception:
                    traceback.print_exc()
    finally:
        for pid in jobs.values():
            _kill(pid)
        shutil.rmtree(Path(path).parent, ignore_errors=True)


def _request(conn: socket.socket) -> tuple[dict, list[int]] | None:
    """A job's request: (its JSON, the stdout and stderr it passed); None if it is cut short or malformed
    (the descriptors it passed closed)."""
    conn.settimeout(10.0)  # a job sends its request at once: a stalled one cannot hold the server
    fds: list[int] = []
    try:
        got = recv(conn, LEN.size, fds=2)
        if got is None:
            return None
        head, fds = got
        body = recv(conn, LEN.unpack(head)[0])
        if body is None or len(fds) != 2:
            raise ValueError("a request cut short")
        request = json.loads(body)
    except (OSError, ValueError):
        for fd in fds:
            os.close(fd)
        return None
    conn.settimeout(None)
    return request, fds


def _ended(signum, frame) -> None:
    raise SystemExit(0)


def _kill(pid: int) -> None:
    try:
        os.kill(pid, signal.SIGTERM)
    except ProcessLookupError:
        pass


def _reap(jobs: dict[socket.socket, int], sel: selectors.BaseSelector) -> None:
    """Send each ended child's exit status to its job, and forget it."""
    for conn, pid in list(jobs.items()):
        done, status = os.waitpid(pid, os.WNOHANG)
        if not done:
            continue
        try:
            conn.sendall(CODE.pack(os.waitstatus_to_exitcode(status)))
        except OSError:
            pass  # the job's script is gone
        try:
            sel.unregister(conn)
        except KeyError:
            pass  # unregistered when its script went away
        conn.close()
        del jobs[conn]


def _main(argv: list[str]) -> None:
    path, parent, rest = argv[0], int(argv[1]), argv[2:]
    modules, warm = (rest[:rest.index("--warm")], rest[rest.index("--warm") + 1:]) if "--warm" in rest else (rest, [])
    signal.signal(signal.SIGTERM, _ended)  # stop(): the finally blocks end the children and remove the folder
    pending = [partial(importlib.import_module, m) for m in (*BASE, *modules)]
    if warm:
        pending.append(partial(_call, warm[0], json.loads(warm[1])))
    serve(path, parent, pending)


def _call(target: str, kwargs: dict) -> None:
    named(target)(**kwargs)


if __name__ == "__main__":
    _main(sys.argv[1:])
