"""The caching table (docs/configuration.md) is what Snakemake does: each row's change, applied to the default config,
makes a dry run plan exactly the jobs the row lists (tests/workflow/caching_table.py builds the table
from those dry runs; ~2 min, so it runs in .ci/run beside the default suite: CAPMAP_CACHING_TABLE=1)."""

from __future__ import annotations

import os

import pytest

from tests.workflow.caching_table import README, readme_table, table

pytestmark = pytest.mark.skipif(os.environ.get("CAPMAP_CACHING_TABLE") != "1",
                                reason="~2 min of dry runs: CAPMAP_CACHING_TABLE=1 (run by .ci/run)")


def test_the_readme_caching_table_is_what_snakemake_reruns(tmp_path):
    generated = table(tmp_path)
    held = readme_table(README.read_text())
    diff = [f"docs: {a}\n  dry runs: {b}" for a, b in zip(held.splitlines(), generated.splitlines()) if a != b]
    assert held == generated, ("the caching table of docs/configuration.md differs from the dry runs (regenerate it "
                               "with python -m tests.workflow.caching_table --write):\n" + "\n".join(diff))
