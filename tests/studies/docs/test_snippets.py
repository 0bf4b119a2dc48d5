"""Every Python snippet the docs show runs when pasted into a ``.py`` file.

The journeys' ``{run} python`` blocks are written to files and run as files while the site
builds (tests/studies/docs/test_docs.py builds it). The pages' plain ```` ```python ````
blocks and README's example are extracted here and each run as its own file, in a folder
holding the files they name: ``my_car.toml`` (the vehicle template) and ``drive.parquet``
(the bundled lane change).
"""

import re
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest

from wheelload.estimators import read_log, write_log
from wheelload.models import vehicle_template
from wheelload.studies.docs.run_blocks import run_block
from wheelload.studies.pipeline.example_log import example_log_path

ROOT = Path(__file__).resolve().parents[3]
PAGES = Path(str(resources.files("wheelload.studies.docs") / "pages"))
FENCE = re.compile(r"^```python\n(.*?)^```$", re.DOTALL | re.MULTILINE)
RUN_FENCE = re.compile(r"^```\{run\} python\n(.*?)^```$", re.DOTALL | re.MULTILINE)


def _snippets() -> list[tuple[str, str]]:
    """(where, code) of every plain python block of the pages and README."""
    found = []
    for page in sorted(PAGES.rglob("*.md")):
        text = page.read_text()
        for block in FENCE.finditer(text):
            line = text[: block.start()].count("\n") + 1
            found.append((f"{page.relative_to(PAGES)}:{line}", block.group(1)))
    readme = (ROOT / "README.md").read_text()
    found += [(f"README.md:{i}", block.group(1)) for i, block in enumerate(FENCE.finditer(readme))]
    return found


SNIPPETS = _snippets()


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A folder with the files the snippets read."""
    folder = tmp_path_factory.mktemp("snippets")
    (folder / "my_car.toml").write_text(vehicle_template())
    write_log(read_log(example_log_path()), folder / "drive.parquet")
    return folder


@pytest.mark.parametrize(("where", "code"), SNIPPETS, ids=[where for where, _ in SNIPPETS])
def test_the_snippet_runs_as_a_file(where, code, folder):
    name = re.sub(r"[^A-Za-z0-9]+", "_", where) + ".py"
    (folder / name).write_text(code)
    done = subprocess.run(
        [sys.executable, name], cwd=folder, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, f"{where}:\n{code}\n{done.stderr}"


def test_the_pages_have_snippets_of_both_kinds():
    """The guide's and README's plain snippets, and the journeys' run blocks."""
    assert len(SNIPPETS) >= 3
    runs = sum(len(RUN_FENCE.findall(page.read_text())) for page in PAGES.rglob("*.md"))
    assert runs >= 7


def test_a_run_block_of_python_runs_as_a_file(tmp_path):
    """A block that starts a process pool works only as a file with its ``__main__`` guard
    (the workers import the main module again): ``python -c`` would hide a missing guard."""
    guarded = (
        "from concurrent.futures import ProcessPoolExecutor\n"
        "import multiprocessing\n"
        "if __name__ == '__main__':\n"
        "    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context('spawn')) as p:\n"
        "        print(p.submit(abs, -3).result(), __file__.rpartition('/')[2])\n"
    )
    printed = run_block("python", guarded, tmp_path, name="pool.py")
    assert printed.split() == ["3", "pool.py"]
    assert (tmp_path / "pool.py").read_text() == guarded
