"""A module whose import lasts until the file named by CAPMAP_TEST_GO exists (at most 120 s): the job-server
test of a server that listens before its imports are done."""

import os
import time
from pathlib import Path

_go = Path(os.environ["CAPMAP_TEST_GO"])
_t = time.monotonic()
while not _go.exists() and time.monotonic() - _t < 120:
    time.sleep(0.05)
