"""The machine a benchmark ran on, printed first so that its figures can be compared and reproduced."""

from __future__ import annotations

import os
import platform
from datetime import date
from importlib.metadata import version


def machine() -> str:
    """'2026-11-24, AMD EPYC 7B13 (2 cores), Linux x86_64, Python 3.11.7, numpy 1.26.4, pin 4.0.0'."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    libs = ", ".join(f"{p} {version(p)}" for p in ("numpy", "pin", "snakemake"))
    return (f"{date.today()}, {cpu} ({os.cpu_count()} cores), {platform.system()} {platform.machine()}, "
            f"Python {platform.python_version()}, {libs}")
