"""The job's side of warm jobs (:mod:`capmap.io.job_server`): send a stage function's name and arguments to
the run's server and wait for its exit status."""

from __future__ import annotations

import json
import os
import socket
import struct
import sys

__all__ = ["ENV", "run_remote", "recv"]

ENV = "CAPMAP_JOB_SERVER"  # the socket's path, in the jobs' environment
LEN = struct.Struct("!I")  # a request's length, before it
CODE = struct.Struct("!i")  # the exit status sent back


def run_remote(path: str, target: str, kwargs: dict) -> int | None:
    """Run ``target`` (``"module:function"``) with ``kwargs`` in a child of the server at ``path``, in this
    process's folder and environment, writing to its stdout and stderr; its exit status, or None when
    there is no server to run it (or it went away before answering)."""
    try:
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.connect(path)
    except OSError:
        return None
    with s:
        try:
            body = json.dumps({"target": target, "kwargs": kwargs, "cwd": os.getcwd(), "env": dict(os.environ)})
        except TypeError:  # an argument JSON cannot carry: the job runs here
            return None
        sys.stdout.flush()
        sys.stderr.flush()
        try:
            data = body.encode()
            socket.send_fds(s, [LEN.pack(len(data)) + data], [1, 2])
            answer = recv(s, CODE.size)
        except OSError:
            return None
    return None if answer is None else CODE.unpack(answer)[0]


def recv(s: socket.socket, n: int, fds: int = 0) -> tuple | bytes | None:
    """n bytes from s (with up to ``fds`` file descriptors sent along: (bytes, fds)); None at end of stream."""
    got, passed = b"", []
    while len(got) < n:
        if fds and not passed:
            chunk, passed, _, _ = socket.recv_fds(s, n - len(got), fds)
        else:
            chunk = s.recv(n - len(got))
        if not chunk:
            for fd in passed:
                os.close(fd)
            return None
        got += chunk
    return (got, passed) if fds else got
