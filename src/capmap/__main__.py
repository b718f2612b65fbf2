"""Command line: ``python -m capmap check [results]`` verifies every catalogued dataset (the main
run's and the atlas') against its sha256 and row count; exit status 1 and one line per problem
when any is missing, damaged or changed."""

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
    chk.add_argument("results", nargs="?", default="results", help="results folder (default: results)")
    args = ap.parse_args(argv)
    results = Path(args.results)
    catalogues = [c for c in (results / "catalogue.parquet", results / "atlas" / "catalogue.parquet") if c.is_file()]
    if not catalogues:
        print(f"capmap: no catalogue under {results} (run snakemake first)", file=sys.stderr)
        return 1
    try:
        problems = [p for c in catalogues for p in verify_catalogue(c, results.parent)]
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    for p in problems:
        print(f"capmap: {p}", file=sys.stderr)
    if not problems:
        print(f"capmap: every catalogued dataset is intact ({', '.join(map(str, catalogues))})")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
