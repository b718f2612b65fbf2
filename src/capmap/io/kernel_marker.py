"""Which numba kernels are compiled already (:mod:`capmap.kernels` compiles them): a marker file in
numba's cache folder (one per content of the kernels' sources, :func:`capmap.numba_folder`) per
numba version and CPU, listing the runs
(robot file, locked joint and angle, dual-arm or not) whose kernels were warmed. Light on purpose: the
workflow checks it before any job without importing the families (a second or two saved per run)."""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import sys
import time
from pathlib import Path

import llvmlite.binding as ll
from numba import __version__ as numba_version
from numba.core import config as numba_config  # not `import numba`: capmap.numba_folder hashes the kernels' files

from capmap.io.fingerprint import file_sha256

__all__ = ["fingerprint", "run_key", "is_warm", "record"]

OWN_CACHES = Path(__file__).resolve().parents[1] / "__pycache__"  # capmap.numba_folder's base by default


def fingerprint() -> str:
    """Hash of what the compiled code depends on: numba's cache folder (named by the content of every source
    file using numba, :func:`capmap._numba_cache_dir`), numba's version, the CPU."""
    h = hashlib.sha256(f"{numba_version} {sys.version} {ll.get_host_cpu_name()} {numba_config.CACHE_DIR}".encode())
    return h.hexdigest()[:16]


def _marker() -> Path:
    """In numba's cache folder (capmap sets it per content of its compiled sources)."""
    return Path(numba_config.CACHE_DIR) / f"kernels-{fingerprint()}.ok"


def run_key(robot_file: str, joint: int, angle_rad: float, dualarm: bool, n_joints: int) -> str:
    """The marker's line for a run: the robot file (its name and content, not its folder: every checkout of
    the same code shares the cache), the locked joint and angle, dual-arm. The angle of the first or last of
    the ``n_joints`` joints is left out: it only moves the locked chain's base or tool, so the chain keeps
    its IK method, and its kernels, at any angle (a what-if on it needs no warm-up); a middle joint's angle
    can change the chain's shape (axes made parallel, a continuum of solutions)."""
    angle = "any" if joint in (1, n_joints) else f"{angle_rad:.6f}"
    return f"{Path(robot_file).name} {file_sha256(robot_file)[:16]} joint {joint} {angle}{' dualarm' if dualarm else ''}"


def is_warm(key: str) -> bool:
    """Whether the marker of this code lists the run ``key`` (:func:`run_key`)."""
    marker = _marker()
    warm = marker.is_file() and key in marker.read_text().splitlines()
    if warm:
        with contextlib.suppress(OSError):
            os.utime(marker)  # in use: not pruned (:func:`record`)
    return warm


UNUSED_DAYS = 30  # a shared cache folder of other sources is removed when no run has used it for this long


def _unused(folder: Path) -> bool:
    """No marker in ``folder`` used (:func:`is_warm`) or written within :data:`UNUSED_DAYS`."""
    stamps = [m.stat().st_mtime for m in folder.glob("kernels-*.ok")] or [folder.stat().st_mtime]
    return time.time() - max(stamps) > UNUSED_DAYS * 86400


def record(key: str) -> None:
    """Add ``key`` to this code's marker (older markers removed, and the cache folders of other sources: in this
    checkout's own __pycache__ all, in a shared cache those unused for :data:`UNUSED_DAYS`); a read-only
    install records nothing
    (its kernels are then warmed, that is loaded from the cache, each time: quick)."""
    marker = _marker()
    done = marker.read_text().splitlines() if marker.is_file() else []
    try:
        marker.parent.mkdir(parents=True, exist_ok=True)
        for old in marker.parent.glob("kernels-*.ok"):
            if old != marker:
                old.unlink()
        for old in marker.parent.parent.glob("numba-" + "[0-9a-f]" * 16):  # caches of other sources
            if old != marker.parent and old.is_dir() and (marker.parent.parent == OWN_CACHES or _unused(old)):
                shutil.rmtree(old, ignore_errors=True)
        marker.write_text("".join(f"{k}\n" for k in (*done, key)))
    except OSError:
        pass
