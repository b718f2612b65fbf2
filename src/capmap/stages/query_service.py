"""``capmap query`` answered by a warm process: a question in about a third of a second instead of the
second and a half a new Python process spends importing numba, Pinocchio and the IK and loading the
compiled kernels.

The first query answers itself and starts this process in the background
(:func:`capmap.stages.query_client.start`): it answers that question once (its imports, its kernels),
forgets what it read, then waits on a Unix socket in capmap's cache folder (its user's only) for
:data:`IDLE_S` seconds. Each later question is answered by a child forked from it for that question
alone: the child reads the config, the robot and the run's maps afresh, as a new process would, and ends
with its answer, so nothing a question reads is remembered between questions (an edited config or a
rebuilt map is seen at once). The socket is named by the content of capmap's sources and the Python that
runs them, so the process never answers for other code."""

from __future__ import annotations

import contextlib
import io
import json
import os
import socket
import sys

from capmap.config.slices import files_of
from capmap.stages.query import answer
from capmap.stages.query_client import read_line, socket_path

__all__ = ["IDLE_S", "serve"]

IDLE_S = 600.0
"""The process ends after this many seconds without a question."""


def _child(conn: socket.socket) -> None:
    """One question, in a forked child: read it, answer it, reply, end."""
    try:
        message = json.loads(read_line(conn))
        os.chdir(message["cwd"])
        said = io.StringIO()
        with contextlib.redirect_stderr(said):  # what the answer says on the way (a compile's announcement)
            rc, out, err = answer(message["request"])
        err = said.getvalue() + err
        conn.sendall(json.dumps({"rc": rc, "out": out, "err": err}).encode() + b"\n")
    finally:
        conn.close()
        os._exit(0)


def serve(warm_request: dict, idle_s: float = IDLE_S) -> None:
    """Warm up on ``warm_request`` (imports, kernels), forget what it read, then answer questions on the
    socket in forked children until ``idle_s`` pass without one."""
    answer(warm_request)
    files_of.cache_clear()  # the only cache keyed by a file's path, not by its content or the code's
    path = socket_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.{os.getpid()}")
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as srv:
        srv.bind(str(tmp))
        os.chmod(tmp, 0o600)
        tmp.replace(path)  # another process may have started meanwhile: the newest answers
        mine = os.stat(path).st_ino
        srv.listen(8)
        srv.settimeout(idle_s)
        while True:
            try:
                conn, _ = srv.accept()
            except TimeoutError:
                break
            if os.fork() == 0:
                srv.close()
                _child(conn)
            conn.close()
            with contextlib.suppress(ChildProcessError):
                while os.waitpid(-1, os.WNOHANG)[0]:
                    pass
    with contextlib.suppress(OSError):
        if os.stat(path).st_ino == mine:  # still ours (not a newer process's)
            path.unlink()


if __name__ == "__main__":  # started by query_client.start: python -m capmap.stages.query_service '<request>'
    serve(json.loads(sys.argv[1]), float(os.environ.get("CAPMAP_QUERY_IDLE_S", IDLE_S)))
