"""Functions the job-server tests run, by name, in the server's children (or in the client itself)."""

import os
import sys
import time
from pathlib import Path

from capmap.errors import CapmapError


def report(out: str, log: str | None = None) -> None:
    """Where and how it ran: its folder, the job's test variable, its process and its parent's."""
    Path(out).write_text(f"{os.getcwd()}\n{os.environ.get('CAPMAP_TEST_VALUE')}\n{os.getpid()}\n{os.getppid()}\n")
    print("a line to the job's stderr", file=sys.stderr)


def modules(out: str, log: str | None = None) -> None:
    """Whether the slow test module is imported in this process (inherited from the server)."""
    Path(out).write_text(str("tests.io.slow_import" in sys.modules))


def fail(log: str | None = None) -> None:
    raise CapmapError("a planted failure")


def wait(out: str, log: str | None = None) -> None:
    """Writes its process id, then runs on (until ended)."""
    Path(out).write_text(str(os.getpid()))
    time.sleep(120)
