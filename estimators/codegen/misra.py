"""MISRA C:2012 findings on the generated C by cppcheck's MISRA add-on (``--addon=misra``).

cppcheck's value-flow pass grows faster than a function's length (the tyre step's kernel of
2700 statements: 30 s): on the KF library's straight-line kernels (two functions of 8 000-9 000
one-line statements each) it does not finish in 15 minutes, while the add-on's rules look at one
statement at a time. So each straight-line run of one-line assignments (the emitted kernels:
:mod:`~wheelload.estimators.kernels.c_emitter`, CasADi's generator in the MHE) is analysed once
per *statement shape*: a copy of the file keeps the first statement of each shape and blanks the
others (the line numbers stay), cppcheck analyses that copy, and a finding on a kept statement
is counted on every statement of its shape. The shape of a statement is its text with the digits
of the names taken away (``w12``, ``x_3``), array indices set to 0, and each number other than
``0`` and ``1`` replaced by ``2`` of its kind (integer, floating, with its suffix), so two
statements of one shape have the same tokens, operators, essential types and literal zeros and
ones: the add-on's rules, all of which look at the tokens, the types and those literals, give
them the same findings. Everything else (declarations, the templated code, the headers) is
analysed as written. One cppcheck run with every translation unit of a folder together
(``--max-configs=1``: the generated code has one configuration) so the whole-program rules
(unused macros and types, identifiers across files, external linkage) see them all.

Each finding is classed by its rule's category (:data:`CATEGORIES`, the MISRA C:2012
guidelines with amendments 1 and 2): mandatory and required rules count as *required*, the
others as *advisory*; a finding whose rule and file the folder's deviation record lists
(:mod:`~wheelload.estimators.codegen.deviations`) is *deviated*.

Example
-------
>>> report = analyse(Path("out/c"))
>>> report.required_open()  # required findings the deviation record does not cover
[]
"""

from __future__ import annotations

import collections
import itertools
import os
import re
import resource
import shutil
import subprocess
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from wheelload.estimators.codegen.deviations import Deviation, read_deviations

#: Categories of the MISRA C:2012 rules the add-on checks (M mandatory, R required, A advisory).
CATEGORIES: dict[str, str] = {
    **{f"1.{k}": c for k, c in zip(range(1, 5), "RARR")},
    **{f"2.{k}": c for k, c in zip(range(1, 9), "RRAAAAAA")},
    "3.1": "R", "3.2": "R", "4.1": "R", "4.2": "A",
    **{f"5.{k}": c for k, c in zip(range(1, 10), "RRRRRRRRA")},
    "6.1": "R", "6.2": "R", "6.3": "R",
    **{f"7.{k}": c for k, c in zip(range(1, 6), "RRRRM")},
    **{f"8.{k}": c for k, c in zip(range(1, 18), "RRRRRRARARARARRAA")},
    **{f"9.{k}": c for k, c in zip(range(1, 8), "MRRRRRM")},
    **{f"10.{k}": c for k, c in zip(range(1, 9), "RRRRARRR")},
    **{f"11.{k}": c for k, c in zip(range(1, 11), "RRRAARRRRR")},
    **{f"12.{k}": c for k, c in zip(range(1, 7), "ARAAMR")},
    **{f"13.{k}": c for k, c in zip(range(1, 7), "RRAARM")},
    **{f"14.{k}": "R" for k in range(1, 5)},
    **{f"15.{k}": c for k, c in zip(range(1, 8), "ARRAARR")},
    **{f"16.{k}": "R" for k in range(1, 8)},
    **{f"17.{k}": c for k, c in zip(range(1, 14), "RRMMAMRAMRAAR")},
    **{f"18.{k}": c for k, c in zip(range(1, 11), "RRRAARRRRM")},
    "19.1": "M", "19.2": "A",
    **{f"20.{k}": c for k, c in zip(range(1, 15), "ARRRARRRRARRRR")},
    **{f"21.{k}": c for k, c in zip(range(1, 22), "RRRRRRRRRRRAMRRRMMMMR")},
    **{f"22.{k}": c for k, c in zip(range(1, 11), "RMRMMMRRRR")},
}  # fmt: skip

#: cppcheck options of every run: C99, the one configuration, findings one per line.
CPPCHECK_OPTIONS = (
    "--addon=misra", "--std=c99", "--language=c", "--max-configs=1", "--inline-suppr",
    "--template={file}\t{line}\t{id}",
)  # fmt: skip
#: A straight-line run shorter than this many statements is analysed as written.
SHORTEST_RUN = 40

_STATEMENT = re.compile(r"^\s*[A-Za-z_]\w*(\[\w+\])? = [^;{}]*;\s*$")
_NUMBER = re.compile(
    r"(?<![\w.])(\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?)([fFuUlL]*)(?![\w.])"
)
_NAME_DIGITS = re.compile(r"\b([A-Za-z_][A-Za-z_]*?)_?\d+\b")
_INDEX = re.compile(r"\[\d+\]")


def category(rule: str) -> str:
    """``required`` (mandatory and required rules) or ``advisory``; an unknown rule counts
    as required."""
    return "advisory" if CATEGORIES.get(rule, "R") == "A" else "required"


def cppcheck() -> str | None:
    """The cppcheck executable with its MISRA add-on, or None."""
    return shutil.which("cppcheck")


@dataclass(frozen=True, order=True)
class Finding:
    """One MISRA finding: file (name in the folder), line, rule (``"10.3"``)."""

    file: str
    line: int
    rule: str

    @property
    def category(self) -> str:
        return category(self.rule)


@dataclass(frozen=True)
class Report:
    """The findings on a folder's generated C, its deviation record, cppcheck's processor
    seconds per translation unit and in all (the whole-program pass included)."""

    findings: tuple[Finding, ...]
    deviations: tuple[Deviation, ...]
    seconds: dict[str, float] = field(default_factory=dict)
    cpu_seconds: float = 0.0

    def deviated(self, finding: Finding) -> bool:
        return any(d.covers(finding.rule, finding.file) for d in self.deviations)

    def required_open(self) -> list[Finding]:
        """Required findings that no deviation covers."""
        return [f for f in self.findings if f.category == "required" and not self.deviated(f)]

    def counts(self) -> dict[str, collections.Counter]:
        """Per file: findings per rule."""
        table: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
        for finding in self.findings:
            table[finding.file][finding.rule] += 1
        return dict(table)

    def to_dict(self) -> dict:
        return {
            "findings": [[f.file, f.line, f.rule] for f in self.findings],
            "seconds": self.seconds,
            "cpu_seconds": self.cpu_seconds,
        }


def shape(statement: str) -> str:
    """The statement with name digits, array indices and numbers other than 0 and 1 made
    generic (see the module docstring)."""

    def number(match: re.Match) -> str:
        digits, suffix = match.groups()
        if digits in ("0", "1"):
            return match.group(0)
        floating = any(mark in digits for mark in ".eE")
        return ("2.0" if floating else "2") + suffix

    text = _NUMBER.sub(number, statement.strip())
    return _INDEX.sub("[0]", _NAME_DIGITS.sub(r"\1", text))


def _runs(lines: Sequence[str]) -> list[range]:
    """Runs of at least :data:`SHORTEST_RUN` consecutive one-line assignments."""
    runs, start = [], None
    for k, line in enumerate([*lines, ""]):
        if _STATEMENT.match(line):
            start = k if start is None else start
        else:
            if start is not None and k - start >= SHORTEST_RUN:
                runs.append(range(start, k))
            start = None
    return runs


def shape_view(text: str) -> tuple[str, dict[int, list[int]]]:
    """The text with each straight-line run cut to one statement per shape (blank lines in
    place of the others), and the lines (1-based) each kept statement stands for."""
    lines = text.splitlines()
    stands_for: dict[int, list[int]] = {}
    for run in _runs(lines):
        first: dict[str, int] = {}
        for k in run:
            kept = first.setdefault(shape(lines[k]), k)
            stands_for.setdefault(kept + 1, []).append(k + 1)
            if kept != k:
                lines[k] = ""
    return "\n".join(lines) + "\n", stands_for


def _sources(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*.c") if p.is_file())


def analyse(
    folder: Path,
    sources: Sequence[Path] | None = None,
    includes: Sequence[Path] = (),
    *,
    shapes: bool = True,
) -> Report:
    """Run cppcheck's MISRA add-on on a folder of generated C (``sources``: its ``.c`` files
    by default; every folder with a header on the include path, then ``includes``, whose
    findings are not reported) and read the folder's deviation record. ``shapes``: analyse
    the straight-line runs once per statement shape (:func:`shape_view`), else as written.

    Raises ``RuntimeError`` without cppcheck or when cppcheck fails.
    """
    executable = cppcheck()
    if executable is None:
        raise RuntimeError("cppcheck not found: install it (apt-get install cppcheck)")
    folder = Path(folder)
    sources = list(sources) if sources is not None else _sources(folder)
    with tempfile.TemporaryDirectory(prefix="wheelload-misra-") as scratch:
        work = Path(scratch)
        stands_for: dict[str, dict[int, list[int]]] = {}
        for path in folder.rglob("*"):
            if path.suffix not in (".c", ".h") or not path.is_file():
                continue
            name = path.relative_to(folder).as_posix()
            (work / name).parent.mkdir(parents=True, exist_ok=True)
            text = path.read_text("utf-8")
            view, stands_for[name] = shape_view(text) if shapes else (text, {})
            (work / name).write_text(view, "utf-8")
        paths = sorted({(work / p.relative_to(folder)).parent for p in folder.rglob("*.h")})
        options = [f"-I{path}" for path in (*paths, *includes)]
        units = [(work / p.relative_to(folder)).as_posix() for p in sources]
        used = resource.getrusage(resource.RUSAGE_CHILDREN)
        findings, seconds = _run(executable, work, options, units)
        now = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = now.ru_utime + now.ru_stime - used.ru_utime - used.ru_stime
    expanded = set()
    for finding in findings:
        lines = stands_for.get(finding.file, {}).get(finding.line, [finding.line])
        expanded.update(Finding(finding.file, line, finding.rule) for line in lines)
    return Report(tuple(sorted(expanded)), read_deviations(folder), seconds, cpu)


def _cpu_seconds(pid: int) -> float | None:
    """Processor seconds of process ``pid`` and its waited-for children (Linux ``/proc``)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return sum(int(value) for value in fields[11:15]) / os.sysconf("SC_CLK_TCK")


def _run(
    executable: str, work: Path, includes: list[str], units: list[str]
) -> tuple[set[Finding], dict[str, float]]:
    """One cppcheck run over ``units``; processor seconds per unit (cppcheck and its add-on,
    from ``/proc``; elsewhere wall-clock seconds) between its progress lines."""
    command = [executable, *CPPCHECK_OPTIONS, *includes, *units]
    seconds: dict[str, float] = {}
    with tempfile.TemporaryFile("w+", encoding="utf-8") as stderr:
        process = subprocess.Popen(
            command, cwd=work, stdout=subprocess.PIPE, stderr=stderr, text=True
        )

        on_proc = _cpu_seconds(process.pid) is not None

        def clock() -> float:
            used = _cpu_seconds(process.pid) if on_proc else None
            return time.perf_counter() if used is None else used

        current, started = None, clock()
        for line in itertools.chain(process.stdout, ["files checked"]):  # type: ignore[arg-type]
            checking = re.match(r"Checking (\S+)", line)
            if checking or "files checked" in line:
                now = clock()
                if current is not None:
                    seconds[current] = seconds.get(current, 0.0) + now - started
                current, started = None, now
                if checking:
                    current = Path(checking.group(1)).relative_to(work).as_posix()
        status = process.wait()
        stderr.seek(0)
        errors = stderr.read()
    if status != 0:
        raise RuntimeError(f"cppcheck failed: {' '.join(command)}\n{errors}")
    findings = set()
    for line in errors.splitlines():
        parts = line.split("\t")
        if len(parts) == 3 and parts[2].startswith("misra-c2012-"):
            file = (work / parts[0]).resolve()
            if not file.is_relative_to(work.resolve()):
                continue  # a header of the include path
            name = file.relative_to(work.resolve()).as_posix()
            findings.add(Finding(name, int(parts[1]), parts[2].removeprefix("misra-c2012-")))
    return findings, seconds
