"""Which numba kernels are compiled already (:mod:`capmap.kernels` compiles them): a marker file beside
numba's cache per hash of the kernels' source files, numba's version and the CPU, listing the runs
(robot file, locked joint and angle, dual-arm or not) whose kernels were warmed. Light on purpose: the
workflow checks it before any job without importing the families (a second or two saved per run)."""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import llvmlite.binding as ll
import numba

from capmap.io.fingerprint import file_sha256

__all__ = ["fingerprint", "run_key", "is_warm", "record"]

PACKAGE = Path(__file__).resolve().parents[1]


def fingerprint() -> str:
    """Hash of what the compiled code depends on: every source file using numba, numba's version, the CPU."""
    h = hashlib.sha256(f"{numba.__version__} {sys.version} {ll.get_host_cpu_name()}".encode())
    for f in sorted(PACKAGE.rglob("*.py")):
        text = f.read_bytes()
        if b"import numba" in text:
            h.update(str(f.relative_to(PACKAGE)).encode() + text)
    return h.hexdigest()[:16]


def _marker() -> Path:
    """Beside numba's cache: NUMBA_CACHE_DIR when set, else the package's __pycache__ folders."""
    where = Path(numba.config.CACHE_DIR) if numba.config.CACHE_DIR else PACKAGE / "__pycache__"
    return where / f"kernels-{fingerprint()}.ok"


def run_key(robot_file: str, joint: int, angle_rad: float, dualarm: bool) -> str:
    """The marker's line for a run: the robot file (path and content), the locked joint and angle, dual-arm."""
    return f"{Path(robot_file).resolve()} {file_sha256(robot_file)[:16]} " \
           f"joint {joint} {angle_rad:.6f}{' dualarm' if dualarm else ''}"


def is_warm(key: str) -> bool:
    """Whether the marker of this code lists the run ``key`` (:func:`run_key`)."""
    marker = _marker()
    return marker.is_file() and key in marker.read_text().splitlines()


def record(key: str) -> None:
    """Add ``key`` to this code's marker (older markers removed); a read-only install records nothing
    (its kernels are then warmed, that is loaded from the cache, each time: quick)."""
    marker = _marker()
    done = marker.read_text().splitlines() if marker.is_file() else []
    try:
        marker.parent.mkdir(exist_ok=True)
        for old in marker.parent.glob("kernels-*.ok"):
            if old != marker:
                old.unlink()
        marker.write_text("".join(f"{k}\n" for k in (*done, key)))
    except OSError:
        pass
