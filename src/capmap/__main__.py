"""Command line.

- ``python -m capmap check [results/<run> ...]`` verifies every catalogued dataset of the runs (the
  main catalogue's, the atlas', the baseline's and the plan-gain experiment's; default: every run
  under ``results/``) against its sha256 and row count; exit status 1 and one line per problem
  when any is missing, damaged or changed, when a named run folder does not exist, or when a run
  has no catalogue.
- ``python -m capmap check-config [FILE ...]`` reads and checks config files with capmap's own
  loader (what the workflow checks before any job, without Snakemake reading the file first:
  Snakemake evaluates YTE templates in a ``--configfile``); exit status 1 and one line on a problem.
- ``python -m capmap arm ROBOT_FILE [--angle-deg A]`` prints, for the robot with each joint locked in
  turn (at A, clipped to the joint's range; default mid-range), the geometry of the remaining
  chain's axes and the IK method it gets, and whether that method finds every branch.
- ``python -m capmap query point X Y Z [--payload M]`` the capacity at that position (the task
  orientation) on every IK branch, named by configuration (binding limit, worst direction, joint
  angles), and the run's voxel values there; ``python -m capmap query line AX AY AZ BX BY BZ
  [--payload M] [--configuration C]`` verifies that straight line on a configuration (default: the
  arm's own at the task start). Both read a run's config (``--configfile``, default
  ``config/config.yaml``), answer without running the pipeline, and print a table (or ``--json``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from capmap.checks import check_run_config
from capmap.config.run import DEFAULT_CONFIG, run_document
from capmap.errors import CapmapError
from capmap.io.datasets import verify_catalogue
from capmap.robots import load, lock_classes
from capmap.stages.query import answer_line, answer_point

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m capmap")
    sub = ap.add_subparsers(dest="command", required=True)
    chk = sub.add_parser("check", help="verify the catalogued datasets (sha256, rows)")
    chk.add_argument("runs", nargs="*", help="run folders, results/<run> (default: every run under results/)")
    cfg = sub.add_parser("check-config", help="read and check config files as the workflow does, before any job")
    cfg.add_argument("files", nargs="*", default=[DEFAULT_CONFIG], help=f"config files (default: {DEFAULT_CONFIG})")
    arm = sub.add_parser("arm", help="the IK classification of a robot with each joint locked in turn")
    arm.add_argument("robot", help="a robot file (config/robots/*.yaml)")
    arm.add_argument("--angle-deg", type=float, default=None, help="the lock angle (default: mid-range)")
    qry = sub.add_parser("query", help="the capacity at a point, or a straight line verified, without the pipeline")
    qsub = qry.add_subparsers(dest="what", required=True)
    qp = qsub.add_parser("point", help="every configuration's capacity at a position (task orientation)")
    qp.add_argument("xyz", nargs=3, type=float, metavar=("X", "Y", "Z"), help="position, m (base frame)")
    ql = qsub.add_parser("line", help="verify the straight line A -> B on one configuration")
    ql.add_argument("ab", nargs=6, type=float, metavar=("AX", "AY", "AZ", "BX", "BY", "BZ"), help="ends, m")
    ql.add_argument("--configuration", default=None, help="e.g. S+E-W+ (default: the arm's own at the task start)")
    for q in (qp, ql):
        q.add_argument("--payload", type=float, default=None, help="payload, kg")
        q.add_argument("--configfile", default=DEFAULT_CONFIG, help=f"the run's config (default: {DEFAULT_CONFIG})")
        q.add_argument("--json", action="store_true", help="answer as JSON")
    args = ap.parse_args(argv)
    if args.command == "query":
        return _query(args)
    if args.command == "check-config":
        return _check_config(args.files)
    if args.command == "arm":
        return _arm(args.robot, args.angle_deg)
    runs = [Path(r) for r in args.runs] or sorted(p for p in Path("results").glob("*") if p.is_dir())
    absent = [r for r in runs if not r.is_dir()]
    bare = [r for r in runs if r.is_dir() and not (r / "catalogue.parquet").is_file()]
    for r in absent:
        print(f"capmap: {r}: no such run folder", file=sys.stderr)
    for r in bare:
        print(f"capmap: {r}: no catalogue.parquet (the run has not finished: snakemake --cores 2 all"
              f"{'' if r.name == 'default' else ' --configfile <its config>'})", file=sys.stderr)
    catalogues = [c for r in runs for c in (r / "catalogue.parquet", r / "atlas" / "catalogue.parquet",
                                            r / "baseline" / "catalogue.parquet", r / "plan" / "gain_catalogue.parquet")
                  if c.is_file()]
    if absent or bare or not catalogues:
        if not catalogues and not absent and not bare:
            print("capmap: no run under results/ (run snakemake first)", file=sys.stderr)
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


def _check_config(files: list[str]) -> int:
    """The files merged in order, as ``--configfile A B`` merges them."""
    source = ", ".join(files)
    try:
        run = check_run_config(run_document(files), source)
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    print(f"capmap: {source}: valid; run {run.name!r}; {run.failure.describe()}; {run.limits.describe()}")
    return 0


def _arm(path: str, angle_deg: float | None) -> int:
    try:
        robot = load(path)
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    print(f"capmap: {robot.name}: {robot.n_joints} joints ({', '.join(robot.joint_names)})")
    for line in lock_classes(robot, angle_deg):
        print(f"  {line}")
    return 0


def _query(args) -> int:
    try:
        if args.payload is not None and not (args.payload >= 0 and args.payload < float("inf")):
            raise CapmapError(f"--payload {args.payload} must be a finite mass >= 0 kg")
        if args.what == "point":
            text = answer_point(args.configfile, args.xyz, args.payload, args.json)
        else:
            text = answer_line(args.configfile, args.ab[:3], args.ab[3:], args.payload, args.configuration, args.json)
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    print(text)
    return 0


def _run_folder(catalogue: Path) -> Path:
    """results/<run> of a catalogue (results/<run>/catalogue.parquet, results/<run>/{atlas,baseline}/catalogue.parquet or
    results/<run>/plan/gain_catalogue.parquet)."""
    return catalogue.parent.parent if catalogue.parent.name in ("atlas", "baseline", "plan") else catalogue.parent


if __name__ == "__main__":
    sys.exit(main())
