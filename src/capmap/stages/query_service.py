"""``capmap query`` answered by a warm process: a question in about a third of a second instead of the
second and a half a new Python process spends importing numba, Pinocchio and the IK and loading the
compiled kernels.

The first query answers itself and starts a server (:func:`serve`) in the background: a process that has
done those imports and loaded those kernels once, then waits on a Unix socket in capmap's cache folder
(readable by its user only) for :data:`IDLE_S` seconds. Each later question is answered by a child
forked from it for that question alone: it reads the config, the robot and the run's maps afresh, as a
new process would, so nothing a question reads is remembered between questions (an edited config or a
rebuilt map is seen at once), and it ends with its answer. The socket is named by the content of
capmap's sources and the Python that runs them, so a server never answers for other code. Set
``CAPMAP_QUERY_SERVER=0`` to answer every query in its own process."""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import socket
import subprocess
import sys
from pathlib import Path

from capmap.io.fingerprint import package_hash

__all__ = ["IDLE_S", "socket_path", "ask", "start", "serve"]

IDLE_S = 600.0
"""The server exits after this many seconds without a question."""


def socket_path() -> Path:
    """The server's socket for this code and this Python, in capmap's cache folder."""
    key = hashlib.sha256(f"{package_hash()} {sys.executable}".encode()).hexdigest()[:16]
    base = Path(os.environ.get("CAPMAP_QUERY_DIR") or os.environ.get("CAPMAP_NUMBA_BASE") or Path.home() / ".cache" / "capmap")
    return base / f"query-{key}.sock"


def enabled() -> bool:
    return os.environ.get("CAPMAP_QUERY_SERVER", "1") != "0"


def ask(argv: list[str], timeout_s: float = 120.0) -> tuple[int, str, str] | None:
    """The server's answer to the command line ``argv`` (exit status, stdout, stderr), or None when no
    server answers (none running, or a stale socket)."""
    path = socket_path()
    if not path.exists():
        return None
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(timeout_s)
            s.connect(str(path))
            s.sendall(json.dumps({"argv": argv, "cwd": os.getcwd()}).encode() + b"\n")
            reply = _read_all(s)
        out = json.loads(reply)
        return int(out["rc"]), str(out["out"]), str(out["err"])
    except (OSError, ValueError, KeyError):
        return None


def start(argv: list[str]) -> None:
    """Start a server in the background, warmed on ``argv`` (a question just answered); quietly nothing
    when it cannot start."""
    try:
        subprocess.Popen([sys.executable, "-m", "capmap.stages.query_service", json.dumps(argv)],
                         stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True, env={**os.environ, "CAPMAP_QUERY_SERVER": "0"})
    except OSError:
        pass


def _answer(main, argv: list[str]) -> tuple[int, str, str]:
    """``main(argv)`` with its stdout and stderr captured."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(argv)
        except SystemExit as exc:  # argparse's usage errors
            rc = exc.code if isinstance(exc.code, int) else 1
    return int(rc or 0), out.getvalue(), err.getvalue()


def _read_all(conn: socket.socket) -> bytes:
    chunks = []
    while True:
        chunk = conn.recv(1 << 16)
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)
        if chunk.endswith(b"\n"):
            return b"".join(chunks)


def _child(conn: socket.socket, main) -> None:
    """One question, in a forked child: read it, answer it, reply, end."""
    try:
        request = json.loads(_read_all(conn))
        os.chdir(request["cwd"])
        rc, out, err = _answer(main, list(request["argv"]))
        conn.sendall(json.dumps({"rc": rc, "out": out, "err": err}).encode() + b"\n")
    finally:
        conn.close()
        os._exit(0)


def serve(warm_argv: list[str], idle_s: float = IDLE_S) -> None:
    """Warm up on ``warm_argv`` (imports, kernels), forget what it read, then answer questions on the
    socket in forked children until ``idle_s`` pass without one. Only the ``query`` command is served."""
    from capmap.__main__ import main
    from capmap.config.slices import files_of

    _answer(main, warm_argv)
    files_of.cache_clear()  # the only cache keyed by a file's path, not its content or the code's
    path = socket_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.{os.getpid()}")
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as srv:
        srv.bind(str(tmp))
        os.chmod(tmp, 0o600)
        tmp.replace(path)  # another server may have started meanwhile: the newest answers
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
                _child(conn, lambda argv: main(argv) if argv[:1] == ["query"] else 1)
            conn.close()
            with contextlib.suppress(ChildProcessError):
                while os.waitpid(-1, os.WNOHANG)[0]:
                    pass
    with contextlib.suppress(OSError):
        if os.stat(path).st_ino == mine:  # still ours (not a newer server's)
            path.unlink()


if __name__ == "__main__":  # started by start(): python -m capmap.stages.query_service '<argv as JSON>'
    serve(json.loads(sys.argv[1]), float(os.environ.get("CAPMAP_QUERY_IDLE_S", IDLE_S)))
