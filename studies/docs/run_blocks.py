"""The ``{run}`` directive: a code block executed while the site builds, shown with its output.

In a page::

    ```{run} shell
    :tail: 5
    wheelload estimate --example
    ```

runs the block (``shell``: bash; ``python``: the building interpreter) in the page's own
working folder (``_run/<page>/`` in the build's source folder, shared by the page's blocks
in order) and shows the code, then what it printed (``:tail: N`` keeps the last N lines).
``:image: FILE`` shows a figure the block wrote. A block that fails stops the build with
its output, so a page never shows a command that does not work.

:func:`run_pages` runs every page's blocks before Sphinx reads (the pages side by side, each
page's blocks in order, as Sphinx would run them) and keeps what they printed in the page's
folder (``.blocks.json``); the directive then shows the kept output, so the journeys run in
parallel however Sphinx groups the pages. A page without kept output runs its blocks as it
is read.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive, directives
from sphinx.errors import ExtensionError

LANGUAGES = {"shell": "bash", "python": "python"}
TIMEOUT = 600.0


def page_folder(srcdir: Path, docname: str) -> Path:
    """The working folder of a page's blocks: ``_run/<page with / as ->``."""
    folder = Path(srcdir) / "_run" / docname.replace("/", "-")
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def run_block(kind: str, code: str, cwd: Path) -> str:
    """Run one block in ``cwd``; its standard output and error, or ExtensionError on failure."""
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="100")
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    command = ["bash", "-e", "-o", "pipefail", "-c", code]
    if kind == "python":
        command = [sys.executable, "-c", code]
    done = subprocess.run(
        command,
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=TIMEOUT,
    )
    if done.returncode != 0:
        raise ExtensionError(
            f"a {kind} block failed (exit {done.returncode}) in {cwd}:\n{code}\n--- output ---\n"
            f"{done.stdout}"
        )
    return done.stdout


#: The file of a page's kept outputs, in its working folder (:func:`run_pages`).
KEPT = ".blocks.json"
_FENCE = re.compile(r"^(`{3,}|~{3,})\{run\}\s+(\S+)\s*$")
_OPTION = re.compile(r"^:[\w-]+:")


@dataclass(frozen=True)
class Block:
    """A ``{run}`` block of a page: its language and code (options left out)."""

    kind: str
    code: str


def page_blocks(text: str) -> list[Block]:
    """The ``{run}`` blocks of a Markdown page, in order (back-tick or tilde fences)."""
    blocks, lines, k = [], text.splitlines(), 0
    while k < len(lines):
        opening = _FENCE.match(lines[k])
        k += 1
        if opening is None:
            continue
        fence, body = opening.group(1), []
        while k < len(lines) and not (
            lines[k].strip().startswith(fence[0] * len(fence))
            and set(lines[k].strip()) == {fence[0]}
        ):
            body.append(lines[k])
            k += 1
        k += 1
        while body and _OPTION.match(body[0]):
            body.pop(0)
        blocks.append(Block(opening.group(2), "\n".join(body).strip("\n")))
    return blocks


def _run_page(srcdir: Path, docname: str, blocks: list[Block]) -> None:
    """Run a page's blocks in order in its folder; keep each output, or the first failure."""
    cwd = page_folder(srcdir, docname)
    kept = []
    for block in blocks:
        entry = {"kind": block.kind, "code": block.code}
        try:
            entry["output"] = run_block(block.kind, block.code, cwd)
        except (ExtensionError, subprocess.TimeoutExpired) as error:
            entry["error"] = str(error)
        kept.append(entry)
        if "error" in entry:
            break
    (cwd / KEPT).write_text(json.dumps(kept))


def run_pages(srcdir: Path, jobs: int) -> None:
    """Run the ``{run}`` blocks of every page under ``srcdir`` before Sphinx reads it, ``jobs``
    pages at a time (module docstring)."""
    srcdir = Path(srcdir)
    pages = {}
    for path in sorted(srcdir.rglob("*.md")):
        docname = path.relative_to(srcdir).with_suffix("").as_posix()
        if not docname.startswith("_") and (blocks := page_blocks(path.read_text())):
            pages[docname] = blocks
    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        for done in [pool.submit(_run_page, srcdir, d, b) for d, b in pages.items()]:
            done.result()


def kept_output(cwd: Path, index: int, kind: str, code: str) -> str | None:
    """Block ``index``'s kept output (:func:`run_pages`), None when the page kept none;
    ExtensionError when it failed, or when the page's blocks are not those that ran."""
    try:
        kept = json.loads((cwd / KEPT).read_text())
    except FileNotFoundError:
        return None
    if index >= len(kept) or (kept[index]["kind"], kept[index]["code"]) != (kind, code):
        raise ExtensionError(f"{cwd}: run block {index + 1} is not the block that ran before")
    if "error" in kept[index]:
        raise ExtensionError(kept[index]["error"])
    return kept[index]["output"]


class RunBlock(Directive):
    """``{run} shell|python`` with options ``:tail: N`` and ``:image: FILE``."""

    required_arguments = 1
    has_content = True
    option_spec = {"tail": directives.nonnegative_int, "image": directives.unchanged}

    def run(self) -> list[nodes.Node]:
        kind = self.arguments[0]
        if kind not in LANGUAGES:
            raise self.error(f"run: give shell or python, got {kind!r}")
        env = self.state.document.settings.env
        cwd = page_folder(env.srcdir, env.docname)
        code = "\n".join(self.content).strip("\n")
        index = env.temp_data.setdefault("run_blocks", 0)
        env.temp_data["run_blocks"] = index + 1
        output = kept_output(cwd, index, kind, code)
        if output is None:
            output = run_block(kind, code, cwd)
        output = output.rstrip("\n")
        if "tail" in self.options:
            output = "\n".join(output.splitlines()[-self.options["tail"] :])
        shown: list[nodes.Node] = [nodes.literal_block(code, code, language=LANGUAGES[kind])]
        if output:
            shown.append(nodes.literal_block(output, output, language="text"))
        if "image" in self.options:
            image = cwd / self.options["image"]
            if not image.is_file():
                raise self.error(f"run: the block wrote no {self.options['image']} in {cwd}")
            uri = "/" + image.relative_to(env.srcdir).as_posix()
            shown.append(nodes.image(uri=uri, alt=self.options["image"]))
        return shown


def setup(app) -> dict:
    """Register the directive (parallel-safe: each page runs in its own folder)."""
    app.add_directive("run", RunBlock)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
