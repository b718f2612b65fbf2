"""Command line: ``python -m capmap check [results/<run> ...]`` verifies every catalogued dataset
of the runs (the main catalogue's and the atlas'; default: every run under ``results/``) against
its sha256 and row count; exit status 1 and one line per problem when any is missing, damaged or
changed."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from capmap.errors import CapmapError
from capmap.io.datasets import verify_catalogue

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m capmap")
    sub = ap.add_subparsers(dest="command", required=True)
    chk = sub.add_parser("check", help="verify the catalogued datasets (sha256, rows)")
    chk.add_argument("runs", nargs="*", help="run folders, results/<run> (default: every run under results/)")
    args = ap.parse_args(argv)
    runs = [Path(r) for r in args.runs] or sorted(p for p in Path("results").glob("*") if p.is_dir())
    catalogues = [c for r in runs for c in (r / "catalogue.parquet", r / "atlas" / "catalogue.parquet") if c.is_file()]
    if not catalogues:
        print(f"capmap: no catalogue under {', '.join(map(str, runs)) or 'results/'} (run snakemake first)",
              file=sys.stderr)
        return 1
    try:  # catalogued paths are relative to the workflow's folder, two levels above results/<run>/
        problems = [p for c in catalogues for p in verify_catalogue(c, _run_folder(c).parent.parent)]
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    for p in problems:
        print(f"capmap: {p}", file=sys.stderr)
    if not problems:
        print(f"capmap: every catalogued dataset is intact ({', '.join(map(str, catalogues))})")
    return 1 if problems else 0


def _run_folder(catalogue: Path) -> Path:
    """results/<run> of a catalogue (results/<run>/catalogue.parquet or results/<run>/atlas/...)."""
    return catalogue.parent.parent if catalogue.parent.name == "atlas" else catalogue.parent


if __name__ == "__main__":
    sys.exit(main())
