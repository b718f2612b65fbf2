"""How long ``capmap query point`` takes, as a user runs it: in its own process (the reference, measured in the
same run) and answered by the warm process (target: <= 1 s). Prints the machine and the median of N runs each.

    python -m tests.benchmarks.bench_query [--runs 5]

The warm process gets a socket folder of its own (CAPMAP_QUERY_DIR) and ends 30 s after the last question.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import tempfile
import time

from tests.benchmarks.machine import machine
from tests.scenario import ROOT

QUESTION = ["capmap", "query", "point", "5", "2", "3", "--payload", "2000"]


def _seconds(env: dict, runs: int) -> list[float]:
    out = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run(QUESTION, cwd=ROOT, env=env, check=True, capture_output=True)
        out.append(time.perf_counter() - t0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    print(f"machine: {machine()}")
    t0 = time.perf_counter()
    subprocess.run(["python", "-c", "pass"], check=True)
    print(f"a Python start: {time.perf_counter() - t0:.2f} s")
    alone = _seconds({**os.environ, "CAPMAP_QUERY_SERVER": "0"}, args.runs)
    print(f"query in its own process (reference): median {statistics.median(alone):.2f} s "
          f"(min {min(alone):.2f}, max {max(alone):.2f})")
    with tempfile.TemporaryDirectory() as folder:
        env = {**os.environ, "CAPMAP_QUERY_SERVER": "1", "CAPMAP_QUERY_DIR": folder, "CAPMAP_QUERY_IDLE_S": "30"}
        first = _seconds(env, 1)[0]
        t0 = time.perf_counter()
        while not any(n.endswith(".sock") for n in os.listdir(folder)) and time.perf_counter() - t0 < 120:
            time.sleep(0.2)
        served = _seconds(env, args.runs)
    print(f"first query (answers, then starts the warm process): {first:.2f} s")
    print(f"query answered by the warm process (target <= 1 s): median {statistics.median(served):.2f} s "
          f"(min {min(served):.2f}, max {max(served):.2f}); {statistics.median(alone) / statistics.median(served):.1f}x "
          "faster than the reference")


if __name__ == "__main__":
    main()
