"""Build the documentation site: pages + API reference + executed journeys → HTML.

The pages (``pages/``, Markdown with MyST) and :mod:`.conf` are copied into a temporary
source folder beside the output, the reference pages are written there
(:func:`.reference.write_reference`), and Sphinx builds with warnings as errors. The site
is built beside ``out`` and renamed into place, so a failed build leaves ``out`` as it was.
MathJax (its ``tex-svg.js``, one file with its fonts) is copied into the site from the
``sphinx-mathjax-offline`` package, so the equations are typeset without a network.
"""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
import tempfile
from importlib import resources
from pathlib import Path

from wheelload.studies.docs.reference import write_reference

MATHJAX_NAME = "mathjax-tex-svg.js"
#: The package (docs extra) whose MathJax the site serves, and the file taken from it.
MATHJAX_PACKAGE = "sphinx-mathjax-offline"
MATHJAX_FILE = ("static", "mathjax", "tex-svg.js")


class DocsBuildError(ValueError):
    """The site could not be built (the message says why)."""


def _copy_pages(source: Path) -> None:
    package = resources.files("wheelload.studies.docs")
    with resources.as_file(package / "pages") as pages:
        shutil.copytree(pages, source, dirs_exist_ok=True)
    with resources.as_file(package / "conf.py") as conf:
        shutil.copy(conf, source / "conf.py")
    (source / "_static").mkdir(exist_ok=True)


def bundled_mathjax() -> Path:
    """MathJax's ``tex-svg.js`` from the ``sphinx-mathjax-offline`` package; a
    :class:`DocsBuildError` naming the install command when it is missing."""
    spec = importlib.util.find_spec(MATHJAX_PACKAGE)
    found = None
    if spec is not None and spec.submodule_search_locations:
        found = Path(next(iter(spec.submodule_search_locations))).joinpath(*MATHJAX_FILE)
    if found is None or not found.is_file():
        raise DocsBuildError(
            f"the offline equations need {MATHJAX_PACKAGE}: install it with "
            "pip install -e '.[docs]' (or give --mathjax FILE, a MathJax tex-svg.js)"
        )
    return found


def build_docs(
    out: Path,
    *,
    force: bool = False,
    strict: bool = True,
    jobs: int = 1,
    mathjax: Path | None = None,
) -> Path:
    """Build the HTML site into ``out``; its ``index.html``.

    ``out`` must be absent or empty unless ``force``. ``strict``: warnings are errors.
    ``jobs``: Sphinx's parallel readers. ``mathjax``: the MathJax ``tex-svg.js`` served with
    the site; by default :func:`bundled_mathjax`'s. Either way the pages need no network.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise DocsBuildError(f"{out} is a file: give a folder for the site")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise DocsBuildError(f"{out} is not empty: give --force to replace it")
    if mathjax is not None and not Path(mathjax).is_file():
        raise DocsBuildError(f"no MathJax file {mathjax}: give the path of tex-svg.js")
    mathjax = bundled_mathjax() if mathjax is None else Path(mathjax)
    out.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=".wheelload-docs-", dir=out.parent))
    try:
        source, html = work / "source", work / "html"
        source.mkdir()
        _copy_pages(source)
        write_reference(source / "reference")
        command = [sys.executable, "-m", "sphinx", "-b", "html", "-q", "-j", str(jobs)]
        if strict:
            command += ["-W", "--keep-going"]
        shutil.copy(mathjax, source / "_static" / MATHJAX_NAME)
        command += ["-D", f"mathjax_path={MATHJAX_NAME}"]
        done = subprocess.run(
            [*command, str(source), str(html)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT
        )
        if done.returncode != 0:
            raise DocsBuildError(
                "the documentation did not build:\n" + done.stdout.decode(errors="replace")
            )
        _replace(html, out)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return out / "index.html"


def _replace(built: Path, out: Path) -> None:
    """Rename the built site into ``out`` (an old ``out`` removed only once it is in place)."""
    old = None
    if out.exists():
        old = out.with_name(f".{out.name}.old")
        shutil.rmtree(old, ignore_errors=True)
        out.rename(old)
    built.rename(out)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
