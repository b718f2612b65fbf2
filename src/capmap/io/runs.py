"""Run folders: each config writes under ``results/<run>/``; what is left there by an earlier config
of the same run (a payload, task, case, shard count or method family since removed) is found, so
that it is never presented as current."""

from __future__ import annotations

from pathlib import Path

__all__ = ["stale_outputs"]


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
