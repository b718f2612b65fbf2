"""Which numba kernels are compiled already (:mod:`capmap.kernels` compiles them): a marker file in
numba's cache folder (one per content of the kernels' sources, :func:`capmap.numba_folder`) per
numba version and CPU, listing the runs
(robot file, locked joint and angle, dual-arm or not) whose kernels were warmed. Light on purpose: the
workflow checks it before any job without importing the families (a second or two saved per run)."""

from __future__ import annotations

import hashlib
import shutil
import sys
from pathlib import Path

import llvmlite.binding as ll
import numba

from capmap.io.fingerprint import file_sha256

__all__ = ["fingerprint", "run_key", "is_warm", "record"]

OWN_CACHES = Path(__file__).resolve().parents[1] / "__pycache__"  # capmap.numba_folder's base by default


def fingerprint() -> str:
    """Hash of what the compiled code depends on: numba's cache folder (named by the content of every source
    file using numba, :func:`capmap._numba_cache_dir`), numba's version, the CPU."""
    h = hashlib.sha256(f"{numba.__version__} {sys.version} {ll.get_host_cpu_name()} {numba.config.CACHE_DIR}".encode())
    return h.hexdigest()[:16]


def _marker() -> Path:
    """In numba's cache folder (capmap sets it per content of its compiled sources)."""
    return Path(numba.config.CACHE_DIR) / f"kernels-{fingerprint()}.ok"


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
        marker.parent.mkdir(parents=True, exist_ok=True)
        for old in marker.parent.glob("kernels-*.ok"):
            if old != marker:
                old.unlink()
        if marker.parent.parent == OWN_CACHES:  # this checkout's caches of earlier sources (a shared base is left alone)
            for old in OWN_CACHES.glob("numba-" + "[0-9a-f]" * 16):
                if old != marker.parent and old.is_dir():
                    shutil.rmtree(old, ignore_errors=True)
        marker.write_text("".join(f"{k}\n" for k in (*done, key)))
    except OSError:
        pass
