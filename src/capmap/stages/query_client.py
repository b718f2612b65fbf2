"""The client side of the warm ``capmap query`` process (:mod:`capmap.stages.query_service`): light on
purpose (sockets and JSON), so that a question answered by the warm process costs a Python start and a
few milliseconds. Set ``CAPMAP_QUERY_SERVER=0`` to answer every query in its own process."""

from __future__ import annotations

import hashlib
import json
import os
import socket
import subprocess
import sys
from pathlib import Path

from capmap.io.fingerprint import package_hash

__all__ = ["socket_path", "enabled", "ask", "start"]


def socket_path() -> Path:
    """The server's socket for this code and this Python, in capmap's cache folder (:func:`capmap._numba_cache_dir`'s
    base; ``CAPMAP_QUERY_DIR`` when set)."""
    key = hashlib.sha256(f"{package_hash()} {sys.executable}".encode()).hexdigest()[:16]
    base = os.environ.get("CAPMAP_QUERY_DIR") or os.environ["CAPMAP_NUMBA_BASE"]  # set by importing capmap
    return Path(base) / f"query-{key}.sock"


def enabled() -> bool:
    return os.environ.get("CAPMAP_QUERY_SERVER", "1") != "0"


def read_line(conn: socket.socket) -> bytes:
    """One newline-ended message from ``conn`` (or what came before it closed)."""
    chunks = []
    while True:
        chunk = conn.recv(1 << 16)
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)
        if chunk.endswith(b"\n"):
            return b"".join(chunks)


def ask(request: dict, timeout_s: float = 120.0, path: Path | None = None) -> tuple[int, str, str] | None:
    """The warm process's answer to a question (:func:`capmap.stages.query.answer`'s), or None when none
    answers (none running, or a stale socket); ``path``: its socket (default :func:`socket_path`)."""
    path = socket_path() if path is None else path
    if not path.exists():
        return None
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(timeout_s)
            s.connect(str(path))
            s.sendall(json.dumps({"request": request, "cwd": os.getcwd()}).encode() + b"\n")
            out = json.loads(read_line(s))
        return int(out["rc"]), str(out["out"]), str(out["err"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def start(request: dict) -> None:
    """Start a warm process in the background, warmed on ``request`` (a question just answered); quietly
    nothing when it cannot start."""
    try:
        subprocess.Popen([sys.executable, "-m", "capmap.stages.query_service", json.dumps(request)],
                         stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True, env={**os.environ, "CAPMAP_QUERY_SERVER": "0"})
    except OSError:
        pass
