"""Logging for the stages: every line to the rule's log file; to the console (stderr) one line per
finished job (its last message, wall time and memory), warnings, and for a long job a progress line at
most every :data:`CONSOLE_EVERY_S` seconds.

Every module logs through ``logging.getLogger(__name__)`` (below the ``capmap`` logger);
:func:`stage_logger` adds the stage's label to each line (``[12:00:01] capacity shard 0 of 4:
500/18500 points ...``). :func:`one_line_errors` turns a :class:`~capmap.errors.CapmapError`
into one ``capmap:`` line on stderr and in the log, and exit status 1.
"""

from __future__ import annotations

import errno
import importlib
import logging
import os
import resource
import signal
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from capmap.errors import CapmapError
from capmap.io.job_client import ENV, run_remote

__all__ = ["stage_logger", "logging_to", "one_line_errors", "named", "call"]

ROOT = "capmap"


class _Labelled(logging.LoggerAdapter):
    def process(self, msg, kwargs):
        return f"{self.extra['label']}: {msg}", kwargs


def stage_logger(name: str, label: str) -> logging.LoggerAdapter:
    """The module logger ``name`` with ``label`` (e.g. 'verify 1500 kg') before every message."""
    return _Labelled(logging.getLogger(name), {"label": label})


CONSOLE_EVERY_S = 30.0
"""A job's progress reaches the console at most this often (its log file gets every line)."""


class _Console(logging.StreamHandler):
    """stderr for a job: warnings at once; an INFO line only when CONSOLE_EVERY_S have passed since the
    job started or since the last one shown; the last INFO line held for :meth:`finish`."""

    def __init__(self) -> None:
        super().__init__(sys.stderr)
        self.shown_at = time.monotonic()
        self.last: logging.LogRecord | None = None

    def emit(self, record: logging.LogRecord) -> None:
        if record.levelno >= logging.WARNING:
            super().emit(record)
            return
        self.last = record
        if time.monotonic() - self.shown_at >= CONSOLE_EVERY_S:
            self.shown_at = time.monotonic()
            super().emit(record)

    def finish(self, tail: str) -> None:
        """The job's one line: its last message and ``tail`` (wall time, memory)."""
        if self.last is not None:
            self.last.msg, self.last.args = f"{self.last.getMessage()} ({tail})", None
            super().emit(self.last)


@contextmanager
def logging_to(log_path: str | Path | None, console: logging.Handler | None = None) -> Iterator[None]:
    """Send the capmap loggers' INFO lines to ``console`` (default: every line to stderr) and, if given,
    appended to ``log_path``; the handlers are closed when the block ends."""
    fmt = logging.Formatter("[%(asctime)s] %(message)s", datefmt="%H:%M:%S")
    handlers: list[logging.Handler] = [console or logging.StreamHandler(sys.stderr)]
    if log_path:
        Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        handlers.append(logging.FileHandler(log_path, mode="a"))
    root = logging.getLogger(ROOT)
    old_level, old_propagate = root.level, root.propagate
    root.setLevel(logging.INFO)
    root.propagate = False
    for h in handlers:
        h.setFormatter(fmt)
        root.addHandler(h)
    try:
        yield
    finally:
        for h in handlers:
            root.removeHandler(h)
            h.close()
        root.setLevel(old_level)
        root.propagate = old_propagate


@contextmanager
def one_line_errors(log_path: str | Path | None = None) -> Iterator[None]:
    """Turn a CapmapError, and a fault of the machine (a full disk, a read-only or vanished folder, no
    memory left), into one ``capmap:`` line on stderr (and the log, when it can still be written) and
    exit status 1."""
    try:
        yield
    except CapmapError as exc:
        _fail(f"capmap: {exc}", log_path)
    except OSError as exc:
        if exc.errno not in MACHINE_FAULTS:
            raise
        where = f"{exc.filename}: " if exc.filename else ""
        _fail(f"capmap: cannot write {where}{exc.strerror or exc} (a fault of the machine: free space or "
              "permissions, then run again; finished outputs are kept)", log_path)
    except MemoryError:
        _fail("capmap: out of memory (the pre-run estimate was exceeded: lower the cores or the map's size, then run "
              "again)", log_path)


MACHINE_FAULTS = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM, errno.EIO}


def _fail(msg: str, log_path) -> None:
    print(msg, file=sys.stderr)
    if log_path:
        try:
            with open(log_path, "a") as f:
                f.write(msg + "\n")
        except OSError:
            pass  # the log's disk is the full one
    raise SystemExit(1) from None


class JobEnded(SystemExit):
    """The job was ended from outside (SIGTERM, or Snakemake gone): it stops, its temp files removed."""


def _ended(signum, frame) -> None:
    raise JobEnded(1)


def _end_with_the_workflow(poll_s: float = 1.0) -> None:
    """A job ends with the workflow that started it: SIGTERM becomes an exception (so ``finally`` blocks remove
    temp files), and a watcher ends the job when its parent process (Snakemake) is gone, however it ended
    (even killed): no job runs on, unseen, after the workflow has stopped."""
    if threading.current_thread() is not threading.main_thread():
        return
    signal.signal(signal.SIGTERM, _ended)
    parent = os.getppid()

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(poll_s)
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=watch, name="capmap-parent-watch", daemon=True).start()


def named(target: str):
    """The function ``target`` names, ``"module:function"`` (its module imported)."""
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


def call(fn, log: str | None = None, **kwargs) -> None:
    """Entry for the thin Snakemake scripts: ``fn(**kwargs)`` with logging to ``log`` and one-line
    errors; the job's wall time and peak memory (resident set) are logged at the end (the sizes
    the cluster profile's per-rule resources are set from). The console gets one line per job
    (:class:`_Console`). ``fn`` may be named, ``"module:function"``: then the run's job server runs it
    when there is one (:mod:`capmap.io.job_server`; this process exits with its status), else this
    process imports and runs it."""
    if isinstance(fn, str):
        status = run_remote(os.environ[ENV], fn, dict(kwargs, log=log)) if os.environ.get(ENV) else None
        if status is not None:
            raise SystemExit(status)
        fn = named(fn)
    t0 = time.perf_counter()
    _end_with_the_workflow()
    console = _Console()
    with one_line_errors(log), logging_to(log, console):
        fn(**kwargs)
        peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: kB
        wall = time.perf_counter() - t0
        last, console.shown_at = console.last, float("inf")  # the job's line below goes to its log file only
        logging.getLogger(f"{ROOT}.job").info(f"job {fn.__name__}: {wall:.1f} s wall, peak memory {peak_mb:.0f} MB")
        console.last = last
        console.finish(f"{wall:.1f} s, {peak_mb:.0f} MB")
