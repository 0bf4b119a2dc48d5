"""README.md stays short and true: its example runs, its links exist, CI runs its test command."""

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_readme_is_at_most_300_lines():
    assert len(README.splitlines()) <= 300


def test_the_ten_line_example_runs_and_meets_its_accuracy(tmp_path):
    """The example prints the pooled RMSE on the bundled lane change; the docs' results page
    gives 27.8 N: 35 N leaves room for a model change without hiding a broken filter."""
    block = re.search(r"## In ten lines\n\n```python\n(.*?)```", README, re.DOTALL).group(1)
    assert len(block.strip().splitlines()) <= 11
    done = subprocess.run(
        [sys.executable, "-c", block], cwd=tmp_path, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    rmse = float(re.search(r"pooled RMSE: ([0-9.]+) N", done.stdout).group(1))
    assert 0 < rmse < 35.0


def test_every_relative_link_exists():
    links = re.findall(r"\]\(([^)#]+)\)", README)
    assert links
    for link in links:
        if not link.startswith(("http://", "https://")):
            assert (ROOT / link).exists(), link


def test_ci_runs_the_test_command_readme_gives():
    command = 'python3 -m pip install -e ".[test]" && python3 -m pytest -q -n auto --durations=25'
    assert command in README
    assert (ROOT / ".ci" / "run").read_text().rstrip().endswith(command)
