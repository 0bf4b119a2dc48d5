"""The ``{run}`` directive: a code block executed while the site builds, shown with its output.

In a page::

    ```{run} shell
    :tail: 5
    wheelload estimate --example
    ```

runs the block (``shell``: bash; ``python``: written to ``block-<line>.py`` and run as a
file by the building interpreter, as a reader who pastes it into a file would) in the
page's own working folder (``_run/<page>/`` in the build's source folder, shared by the
page's blocks in order) and shows the code, then what it printed (``:tail: N`` keeps the
last N lines).
``:image: FILE`` shows a figure the block wrote. A block that fails stops the build with
its output, so a page never shows a command that does not work.
"""

from __future__ import annotations

import os
import subprocess
import sys
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


def run_block(kind: str, code: str, cwd: Path, *, name: str = "block.py") -> str:
    """Run one block in ``cwd``; its standard output and error, or ExtensionError on failure.

    A python block is written to ``cwd / name`` and run as that file (a process pool or a
    Dask cluster it starts then needs its ``if __name__ == "__main__":`` guard, as in a
    reader's own file)."""
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="100")
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    command = ["bash", "-e", "-o", "pipefail", "-c", code]
    if kind == "python":
        (Path(cwd) / name).write_text(code if code.endswith("\n") else code + "\n")
        command = [sys.executable, name]
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
        code = "\n".join(self.content)
        output = run_block(kind, code, cwd, name=f"block-{self.lineno}.py").rstrip("\n")
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
