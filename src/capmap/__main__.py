"""Command line.

- ``capmap check [results/<run> ...]`` verifies every catalogued dataset of the runs (the
  main catalogue's, the atlas', the baseline's, the advice's and the plan-gain experiment's; default: every run
  under ``results/``) against its sha256 and row count; exit status 1 and one line per problem
  when any is missing, damaged or changed, when a named run folder does not exist, or when a run
  has no catalogue.
- ``capmap check-config [FILE ...]`` reads and checks config files with capmap's own
  loader (what the workflow checks before any job, without Snakemake reading the file first:
  Snakemake evaluates YTE templates in a ``--configfile``); exit status 1 and one line on a problem.
- ``capmap arm ROBOT_FILE [--angle-deg A]`` prints, for the robot with each joint locked in
  turn (at A, clipped to the joint's range; default mid-range), the geometry of the remaining
  chain's axes and the IK method it gets, and whether that method finds every branch.
- ``capmap query point X Y Z [--payload M]`` the capacity at that position (the task orientation) on
  every IK branch, named by configuration (binding limit, worst direction; the arm's own marked; a
  verdict for the payload), and the run's voxel values there (every voxel the point touches);
  ``capmap query line AX AY AZ BX BY BZ
  [--payload M] [--configuration C]`` verifies that straight line on a configuration (default: the
  arm's own at the task start). Both read a run's config (``--configfile``, default
  ``config/config.yaml``), answer without running the pipeline, and print a table (or ``--json``); a
  warm process answers after the first (:mod:`capmap.stages.query_service`).
- ``capmap catalogue [RUN]`` lists a run's datasets: the names :func:`capmap.load` takes, their rows and
  what they hold.
- ``capmap advise [CONFIG] [--joint J] [--cores N] [-n]`` runs the lock-angle advice of joint J (default: the
  config's ``advice.joints`` and the failure-tolerant map) and prints where to brake each joint and what the
  worst task keeps there.
- ``capmap run [CONFIG] [TARGET ...] [--cores N] [-n]`` checks CONFIG (default ``config/config.yaml``) with
  capmap's own loader, then runs the workflow on it (``snakemake --config configfile=CONFIG``: Snakemake
  never opens the file itself, so a config one did not write cannot run code or hang the reader).

``python -m capmap ...`` is the same. A usage error is one ``capmap:`` line and exit status 1; every command
that answers takes ``--json``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

from capmap.config.defaults import DEFAULT_CONFIG
from capmap.errors import CapmapError

# each command imports what it runs when it runs (--help and a usage error answer at once, a query
# does not load the dual-arm or reconfiguration families)

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """argparse with a usage error as one ``capmap:`` line and exit status 1 (not argparse's 2 and usage text)."""

    def error(self, message: str):
        what = self.prog.removeprefix("capmap").strip()
        print(f"capmap: {what + ': ' if what else ''}{message} (see {self.prog} --help)", file=sys.stderr)
        sys.exit(1)


def _finite(text: str) -> float:
    """A command-line number: finite (nan and inf are refused as argparse refuses 'abc')."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def _parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="capmap", description="Load-carrying capacity maps of a manipulator with a locked joint, "
                 "their plans and verification; torque-limited following; boom reconfiguration; dual-arm assembly.")
    sub = ap.add_subparsers(dest="command", required=True, parser_class=_Parser)
    run = sub.add_parser("run", help="check a config with capmap's loader, then run the workflow on it")
    run.add_argument("config", nargs="?", default=DEFAULT_CONFIG, help=f"the run's config (default: {DEFAULT_CONFIG})")
    run.add_argument("targets", nargs="*", default=["all"], help="workflow targets (default: all)")
    run.add_argument("--cores", default="2", help="cores for the jobs (default: 2)")
    run.add_argument("-n", "--dry-run", action="store_true", help="show the jobs without running them")
    adv = sub.add_parser("advise", help="where to brake a joint: its lock angle swept, the run's tasks verified at each")
    adv.add_argument("config", nargs="?", default=DEFAULT_CONFIG, help=f"the run's config (default: {DEFAULT_CONFIG})")
    adv.add_argument("--joint", type=int, default=None,
                     help="the joint, 1-based (default: advice.joints, and the failure-tolerant map)")
    adv.add_argument("--cores", default="2", help="cores for the jobs (default: 2)")
    adv.add_argument("-n", "--dry-run", action="store_true", help="show the jobs without running them")
    chk = sub.add_parser("check", help="verify the catalogued datasets (sha256, rows)")
    chk.add_argument("runs", nargs="*", help="run folders, results/<run> (default: every run under results/)")
    cfg = sub.add_parser("check-config", help="read and check config files as the workflow does, before any job")
    cfg.add_argument("files", nargs="*", default=[DEFAULT_CONFIG], help=f"config files (default: {DEFAULT_CONFIG})")
    cat = sub.add_parser("catalogue", help="the datasets of a run: name (for capmap.load), rows, what they hold")
    cat.add_argument("run", nargs="?", default="default", help="a run's name or folder (default: default)")
    cat.add_argument("--results", default="results", help="the results folder (default: results)")
    arm = sub.add_parser("arm", help="the IK classification of a robot with each joint locked in turn")
    arm.add_argument("robot", help="a robot file (config/robots/*.yaml)")
    arm.add_argument("--angle-deg", type=_finite, default=None, help="the lock angle (default: mid-range)")
    qry = sub.add_parser("query", help="the capacity at a point, or a straight line verified, without the pipeline")
    qsub = qry.add_subparsers(dest="what", required=True)
    qp = qsub.add_parser("point", help="every configuration's capacity at a position (task orientation)")
    for name in ("x", "y", "z"):  # one positional each: argparse's --help cannot show a tuple metavar of nargs=3
        qp.add_argument(name, type=_finite, help=f"position {name}, m (base frame)")
    ql = qsub.add_parser("line", help="verify the straight line A -> B on one configuration")
    for name in ("ax", "ay", "az", "bx", "by", "bz"):
        ql.add_argument(name, type=_finite, help=f"{'start' if name[0] == 'a' else 'end'} {name[1]}, m (base frame)")
    ql.add_argument("--configuration", default=None, help="e.g. S+E-W+ (default: the arm's own at the task start)")
    qp.add_argument("--joints", action="store_true", help="also each configuration's joint angles")
    for q in (qp, ql):
        q.add_argument("--payload", type=_finite, default=None, help="payload, kg (adds the verdict and margins)")
        q.add_argument("--configfile", default=DEFAULT_CONFIG, help=f"the run's config (default: {DEFAULT_CONFIG})")
    for p in (chk, cfg, cat, arm, qp, ql):
        p.add_argument("--json", action="store_true", help="answer as JSON (errors stay one line on stderr)")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "run":
        return _run(args)
    if args.command == "advise":
        from capmap.stages.advise_command import advise

        return advise(args, _run)
    if args.command == "query":
        return _query(args)
    if args.command == "check-config":
        return _check_config(args.files, args.json)
    if args.command == "arm":
        return _arm(args.robot, args.angle_deg, args.json)
    if args.command == "catalogue":
        return _catalogue(args.run, args.results, args.json)
    return _check(args.runs, args.json)


def _check(run_folders: list[str], as_json: bool) -> int:
    from capmap.io.datasets import verify_catalogue

    runs = [Path(r) for r in run_folders] or sorted(p for p in Path("results").glob("*") if p.is_dir())
    absent = [r for r in runs if not r.is_dir()]
    bare = [r for r in runs if r.is_dir() and not (r / "catalogue.parquet").is_file()]
    for r in absent:
        print(f"capmap: {r}: no such run folder", file=sys.stderr)
    for r in bare:
        print(f"capmap: {r}: no catalogue.parquet (the run has not finished: snakemake --cores 2 all"
              f"{'' if r.name == 'default' else ' --configfile <its config>'})", file=sys.stderr)
    catalogues = [c for r in runs for c in (r / "catalogue.parquet", r / "atlas" / "catalogue.parquet",
                                            r / "baseline" / "catalogue.parquet", r / "advice" / "catalogue.parquet",
                                            r / "plan" / "gain_catalogue.parquet")
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
    if as_json:
        print(json.dumps({"catalogues": list(map(str, catalogues)), "intact": not problems, "problems": problems}))
    elif not problems:
        print(f"capmap: every catalogued dataset is intact ({', '.join(map(str, catalogues))})")
    return 1 if problems else 0


def _check_config(files: list[str], as_json: bool = False) -> int:
    """The files merged in order, as ``--configfile A B`` merges them."""
    from capmap.checks import check_run_config
    from capmap.config.run import run_document

    source = ", ".join(files)
    try:
        run = check_run_config(run_document(files), source)
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    if as_json:
        print(json.dumps({"files": files, "valid": True, "run": run.name, "lock": run.failure.describe(),
                          "limits": run.limits.describe()}))
    else:
        print(f"capmap: {source}: valid; run {run.name!r}; {run.failure.describe()}; {run.limits.describe()}")
    return 0


def _arm(path: str, angle_deg: float | None, as_json: bool) -> int:
    from capmap.robots import load, lock_classes

    try:
        robot = load(path)
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    lines = lock_classes(robot, angle_deg)
    if as_json:
        print(json.dumps({"robot": robot.name, "joints": list(robot.joint_names), "locks": list(lines)}))
        return 0
    print(f"capmap: {robot.name}: {robot.n_joints} joints ({', '.join(robot.joint_names)})")
    for line in lines:
        print(f"  {line}")
    return 0


def _catalogue(run: str, results: str, as_json: bool) -> int:
    """A run's datasets: the names capmap.load takes, their rows and what they hold."""
    from capmap.io.catalogue import catalogue

    try:
        cat = catalogue(run, results)
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    if as_json:
        print(cat[["name", "description", "row", "path", "rows", "units"]].to_json(orient="records", indent=1))
        return 0
    w = max(map(len, cat.name))
    for r in cat.itertuples():
        print(f"{r.name:<{w}}  {r.rows:>9,} rows  {r.path}")
        print(textwrap.fill(getattr(r, "description", "(no description: a catalogue of an older capmap)"), 100,
                            initial_indent="    ", subsequent_indent="    "))
    print(f"capmap: {len(cat)} datasets; in pandas: capmap.load({run!r}, name) (docs/outputs.md)")
    return 0


def _query(args) -> int:
    """Answered by the warm process when one runs (:mod:`capmap.stages.query_client`), else here (and one is
    started for the next question)."""
    from capmap.stages import query_client as client

    request = {"what": args.what, "configfile": args.configfile, "payload_kg": args.payload, "json": args.json,
               **({"point_m": [args.x, args.y, args.z], "joints": args.joints} if args.what == "point" else
                  {"a_m": [args.ax, args.ay, args.az], "b_m": [args.bx, args.by, args.bz],
                   "configuration": args.configuration})}
    answered = client.ask(request) if client.enabled() else None
    if answered is None:
        from capmap.stages.query import answer

        answered = answer(request)
        if client.enabled():
            client.start(request)  # the next question is answered by a warm process
    rc, out, err = answered
    sys.stdout.write(out)
    sys.stderr.write(err)
    return rc


def _run(args) -> int:
    """Check the config as the workflow will, then hand over to Snakemake naming the file through
    ``--config configfile=`` (Snakemake does not read it; capmap's loader does, bounded)."""
    config = str(Path(args.config).absolute()) if args.config != DEFAULT_CONFIG else None
    if _check_config([args.config]):
        return 1
    snakefile = Path("Snakefile")
    if not snakefile.is_file():
        snakefile = Path(__file__).resolve().parents[2] / "Snakefile"  # the checkout this package is installed from
    exe = shutil.which("snakemake")
    if exe is None or not snakefile.is_file():
        print("capmap: run: needs snakemake and capmap's Snakefile (run it in the capmap checkout)", file=sys.stderr)
        return 1
    cmd = [exe, "-s", str(snakefile), "--cores", str(args.cores), *args.targets, *(["-n"] if args.dry_run else []),
           *(["--config", f"configfile={config}"] if config else [])]
    print(f"capmap: {' '.join(cmd)}", file=sys.stderr)
    return _snakemake(cmd)


# Snakemake's scheduling chatter (its set-up, two lines per job, its step counts): each job's own capmap line
# says what ran, and the job table is summed up in one line
_CHATTER = re.compile(r"^(Select jobs to execute\.\.\.|Execute \d+ jobs\.\.\.|Using shell: .*|Conda environments: ignored|"
                      r"Assuming unrestricted shared filesystem usage\.|Building DAG of jobs\.\.\.|"
                      r"Using workflow specific profile .*|\[\w{3} \w{3} +\d+ [\d:]+ \d{4}\]|Finished jobid: .*|"
                      r"\d+ of \d+ steps \(\d+%\) done|Provided cores: \d+|Rules claiming more threads .*|"
                      r"Job stats:|job +count|-+ +-+|)$")


def _snakemake(cmd: list[str]) -> int:
    """Run Snakemake, its console without the scheduling chatter (its log under .snakemake/log keeps
    every line); Ctrl-C reaches it as it would from the terminal (same process group)."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    jobs: list[str] | None = None  # inside the job table
    try:
        for line in proc.stdout:
            text = line.rstrip("\n")
            if text == "Job stats:":
                jobs = []
            elif jobs is not None and text.startswith("total"):
                print(f"capmap: {text.split()[-1]} jobs to run: {', '.join(j for j in jobs if j != 'all')}",
                      file=sys.stderr, flush=True)
                jobs = None
                continue
            elif jobs is not None and re.match(r"^\w+ +\d+$", text):
                name, n = text.split()
                jobs.append(name if n == "1" else f"{name} x{n}")
                continue
            if not _CHATTER.match(text):
                sys.stderr.write(line)
                sys.stderr.flush()
    except KeyboardInterrupt:
        pass
    return proc.wait()


def entry() -> None:
    """The ``capmap`` command (``[project.scripts]``)."""
    try:
        sys.exit(main())
    except BrokenPipeError:  # capmap catalogue | head: the reader has what it wanted
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)


def _run_folder(catalogue: Path) -> Path:
    """results/<run> of a catalogue (results/<run>/catalogue.parquet, results/<run>/{atlas,baseline,advice}/catalogue.parquet or
    results/<run>/plan/gain_catalogue.parquet)."""
    return catalogue.parent.parent if catalogue.parent.name in ("atlas", "baseline", "advice", "plan") else catalogue.parent


if __name__ == "__main__":
    entry()
