"""The Python snippets of the README and docs/ run: each ```python block is executed on the outputs of the
shared tiny pipeline run, seen as results/default/ (the pages' paths), and must not raise."""

from __future__ import annotations

import re

import pytest

from tests.scenario import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCKS = [b for page in PAGES for b in re.findall(r"```python\n(.*?)```", page.read_text(), re.S)]


def test_the_readme_has_python_snippets():
    assert BLOCKS


@pytest.mark.slow  # on the shared tiny run: .ci/run runs it (-m slow)
@pytest.mark.parametrize("code", BLOCKS, ids=[f"block{i + 1}" for i in range(len(BLOCKS))])
def test_a_readme_snippet_runs_on_a_run_s_outputs(run_dir, tmp_path, monkeypatch, code):
    work, _ = run_dir
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "default").symlink_to(work / "results" / "tiny")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
