"""Run folders: each config writes under ``results/<run>/``; what is left there by an earlier config
of the same run (a payload, task, case, shard count or method family since removed) is found, so
that it is never presented as current."""

from __future__ import annotations

import os
from pathlib import Path

from capmap.errors import CapmapError

__all__ = ["stale_outputs", "check_writable"]


def stale_outputs(run_dir: str | Path, current: dict[str, list[str]]) -> list[str]:
    """Paths under ``run_dir`` matching one of the glob patterns of ``current`` (relative to
    ``run_dir``) but not among that pattern's current paths (the same form, relative to
    ``run_dir``), sorted. A pattern whose list is empty marks everything it matches as stale.

    >>> stale_outputs("results/default", {"verify/payload_*kg": ["verify/payload_1500kg"]})  # doctest: +SKIP
    ['results/default/verify/payload_4000kg']
    """
    run_dir = Path(run_dir)
    stale = []
    for pattern, paths in current.items():
        keep = {str(run_dir / p) for p in paths}
        stale += [str(p) for p in run_dir.glob(pattern) if str(p) not in keep]
    return sorted(set(stale))


def check_writable(run_dir: str | Path) -> None:
    """The run's output folder exists or can be made, and takes a file: else one
    line naming it (:class:`CapmapError`) (before any job: a read-only or full results folder is known before the first job)."""
    run_dir = Path(run_dir)
    probe = run_dir / f".capmap-write-check.{os.getpid()}"
    try:
        run_dir.mkdir(parents=True, exist_ok=True)
        probe.write_bytes(b"capmap")
        probe.unlink()
    except OSError as exc:
        raise CapmapError(f"{run_dir}: the run's outputs cannot be written there ({exc.strerror or exc}): free space, "
                          "fix its permissions, or run from a folder you can write") from None
