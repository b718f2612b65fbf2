"""The ``capmap advise`` command: where to brake a joint, through the workflow's advice targets."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Callable

import pandas as pd

from capmap.checks import check_run_config
from capmap.config.run import run_document
from capmap.errors import CapmapError

__all__ = ["advise"]


def advise(args, run_workflow: Callable[[argparse.Namespace], int]) -> int:
    """``capmap advise``: the advice's targets of a checked config (one joint's, or ``advise``) through
    ``run_workflow`` (``capmap run``'s), then each joint's recommendation, one line each."""
    try:
        run = check_run_config(run_document([args.config]), args.config)
        n = len(run.failure.q_start_deg)
        if run.advice is None:
            raise CapmapError("advise: the config has no atlas section: the advice uses the atlas' maps")
        if args.joint is not None and not 1 <= args.joint <= n:
            raise CapmapError(f"advise: --joint {args.joint} is not a joint: the arm has joints 1..{n}")
    except CapmapError as exc:
        print(f"capmap: {exc}", file=sys.stderr)
        return 1
    joints = [args.joint] if args.joint is not None else list(run.advice.joints_of(run.failure.joint))
    folder = Path("results") / run.name / "advice"
    args.targets = [str(folder / f"joint{args.joint}" / "margins.png")] if args.joint is not None else ["advise"]
    rc = run_workflow(args)
    for j in [] if rc or args.dry_run else joints:
        a = pd.read_parquet(folder / f"joint{j}" / "advice.parquet").iloc[0]
        print(f"joint {j}: brake it at {a.recommended_angle_deg:g} deg: the worst task ({a.worst_task}) keeps "
              f"{a.worst_margin_pct:+.1f} % (a step either side: {a.neighbours_worst_margin_pct:+.1f} %), "
              f"{a.tasks_carried} of {a.n_tasks} tasks carried (where it stands, {a.stands_at_deg:g} deg: "
              f"{a.stands_at_worst_margin_pct:+.1f} %); {folder / f'joint{j}' / 'margins.png'}")
    return rc
