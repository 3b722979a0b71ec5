"""The library's examples in README.md and docs/library.md run: each ``<!-- sample:
python -->`` block is a script run against the built-in simulator in a fresh interpreter
(a private HOME, no config file), which must exit 0 and say nothing on stderr. What an
example shows of a value, it asserts."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.doc_samples import PYTHON_PAGES, Sample, read_page, run_python

SAMPLES = [
    sample for page in PYTHON_PAGES for sample in read_page(page).samples if sample.kind == "python"
]


def test_every_python_block_is_a_checked_sample() -> None:
    unmarked = [f"{page}:{line}" for page in PYTHON_PAGES for line in read_page(page).unmarked]
    assert unmarked == [], "mark these as <!-- sample: python -->"
    assert {sample.page for sample in SAMPLES} == set(PYTHON_PAGES)
    assert len([s for s in SAMPLES if s.page == "docs/library.md"]) >= 8


def test_an_unmarked_python_block_is_found() -> None:
    found = read_page("x.md", "```python\nimport rac_console\n```\n")
    assert found.unmarked == [1] and found.samples == []


@pytest.mark.slow
@pytest.mark.parametrize("sample", SAMPLES, ids=[s.name for s in SAMPLES])
def test_the_example_runs(sample: Sample, tmp_path: Path, env: dict[str, str]) -> None:
    done = run_python("\n".join(sample.lines) + "\n", tmp_path, env)
    assert (done.returncode, done.stderr) == (0, ""), f"{sample.name}:\n{done.stderr}"
