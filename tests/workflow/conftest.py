"""The tiny pipeline run shared by the workflow tests (once per session)."""

from __future__ import annotations

import pytest

from tests.workflow.runs import config_file, snakemake_run


@pytest.fixture(scope="session")
def run_dir(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pipeline")
    cfg = config_file(tmp)
    res = snakemake_run(tmp, cfg)
    assert res.returncode == 0, res.stderr[-3000:]
    (tmp / "snakemake_stderr.txt").write_text(res.stderr)  # the run's console, for the headline's test
    return tmp, cfg
