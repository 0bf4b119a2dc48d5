"""The MISRA C:2012 deviation record shipped beside the generated C (``MISRA_DEVIATIONS.md``).

Each deviation names a rule, the generated files it covers (shell patterns, ``PREFIX`` for the C
symbol prefix), where in them the pattern is, and why the code keeps it. The generators write
the record (:func:`write_deviation_record`) into the folder they write;
:func:`~wheelload.estimators.codegen.misra.analyse` reads it back from the folder
(:func:`read_deviations`), so the record that ships is the record that is checked.

Example
-------
>>> write_deviation_record(Path("out/c"), KF_DEVIATIONS, "wheelload_kf")
"""

from __future__ import annotations

import fnmatch
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from wheelload.estimators.logs.output_files import write_text

#: The record's file name in a generated folder.
RECORD_NAME = "MISRA_DEVIATIONS.md"


@dataclass(frozen=True, kw_only=True)
class Deviation:
    """A rule the generated code departs from, in which files, where and why."""

    rule: str  # "10.3"
    files: tuple[str, ...]  # shell patterns of file names in the folder
    where: str
    why: str

    def covers(self, rule: str, file: str) -> bool:
        return rule == self.rule and any(fnmatch.fnmatch(file, p) for p in self.files)

    def for_prefix(self, prefix: str) -> Deviation:
        """The deviation with ``PREFIX`` replaced by the C symbol prefix."""
        return Deviation(
            rule=self.rule,
            files=tuple(p.replace("PREFIX", prefix) for p in self.files),
            where=self.where.replace("PREFIX", prefix),
            why=self.why.replace("PREFIX", prefix),
        )


#: Files of the host-side programs written beside the library: the CSV example and the self-test.
_HOST = ("PREFIX_example.c", "PREFIX_selftest.c")
_HOST_WHY = (
    "host-side program (CSV log in, CSV out; timing on a PC), not part of the ECU build, "
    "which is PREFIX.c and PREFIX_tyre.c"
)


def _host(rule: str, where: str, why: str) -> Deviation:
    return Deviation(rule=rule, files=_HOST, where=where, why=f"{_HOST_WHY}: {why}")


#: Deviations of the two-stage KF library and its tyre step (PREFIX.c, PREFIX_tyre.c).
LIBRARY_DEVIATIONS: tuple[Deviation, ...] = (
    Deviation(
        rule="8.14",
        files=("PREFIX.c",),
        where="PREFIX_step_batch: one restrict pointer per row of the struct-of-arrays storage",
        why="the rows of a batch never overlap (the caller's arrays, row k at k * n); restrict "
        "states it so that the compiler vectorises the loop over filters, the batched step's "
        "purpose; the single step (PREFIX_step) has no restrict",
    ),
)
#: Deviations of the FMU wrapper (PREFIX_fmu.c).
FMU_DEVIATIONS: tuple[Deviation, ...] = (
    Deviation(
        rule="5.5",
        files=("PREFIX_fmu.c",),
        where="the fmi3 functions' definitions",
        why="the FMI 3.0 standard's fmi3Functions.h defines each function name as a macro "
        "(FMI3_FUNCTION_PREFIX) and the FMU must define the functions under those names",
    ),
    Deviation(
        rule="11.1",
        files=("PREFIX_fmu.c",),
        where="(void) of unused callback parameters (intermediateUpdate, clockUpdate, "
        "lockPreemption)",
        why="a conversion of a function pointer to void, which the rule's exception 2 allows; "
        "the add-on does not know the exception",
    ),
    Deviation(
        rule="21.3",
        files=("PREFIX_fmu.c",),
        where="calloc in fmi3InstantiateCoSimulation, free in fmi3FreeInstance",
        why="FMI 3.0 gives an FMU no memory callbacks: the importer asks for instances at run "
        "time and the FMU allocates each one once, at instantiation, never in a step",
    ),
    Deviation(
        rule="21.6",
        files=("PREFIX_fmu.c",),
        where="snprintf into the message of the FMI logger callback",
        why="FMI's logMessage takes a formatted text; snprintf is bounded by the buffer size "
        "and runs only when the importer enabled logging or on a refused call",
    ),
)
#: Deviations of the host-side example program and self-test.
HOST_DEVIATIONS: tuple[Deviation, ...] = (
    _host(
        "21.1",
        "#define _POSIX_C_SOURCE",
        "asks the C library for POSIX fchmod/fdopen/clock_gettime",
    ),
    _host("21.6", "#include <stdio.h>", "reads and writes files"),
    _host("21.7", "atoi of a command-line count", "command-line parsing on a PC"),
    _host("21.9", "qsort of the timings", "median of the timings on a PC"),
    _host("21.10", "#include <time.h>, clock_gettime", "timing on a PC"),
    _host("2.2", "the row type of the CSV reader", "cppcheck counts its typedef as dead code"),
    _host("7.1", "0666 file mode", "POSIX file modes are octal by convention"),
    _host("8.6", "main", "each program defines its own main; they are linked apart"),
    _host("10.3", "int and double conversions in the parsing and the test signal", "parsing"),
    _host("10.4", "size_t against int counts", "parsing"),
    _host("10.8", "(size_t)(pointer difference)", "parsing"),
    _host("14.2", "for loops over characters and lines", "parsing"),
    _host("14.4", "character class tests, ferror", "parsing"),
    _host("15.7", "if ... else if without else", "parsing"),
    _host("17.7", "fprintf's return value unused", "messages on stderr"),
    _host("22.8", "strtod without errno reset", "range errors are caught by isfinite"),
)
#: Deviations of a KF folder written by ``wheelload codegen``: the library and the host programs.
KF_DEVIATIONS: tuple[Deviation, ...] = (*LIBRARY_DEVIATIONS, *HOST_DEVIATIONS)

#: OSQP's own sources and headers in an embedded MHE folder, as OSQP's code generator copies them.
_OSQP = ("osqp/src/*.c", "osqp/inc/*")
#: The required rules OSQP's sources depart from (cppcheck's add-on on OSQP 1.0's embedded code).
_OSQP_RULES = (
    "3.1", "5.8", "8.4", "10.3", "10.4", "10.6", "11.8", "11.9", "14.4", "15.6", "15.7", "16.3",
    "16.4", "17.7", "21.1",
)  # fmt: skip
_MHE_MAIN = ("wheelload_mhe_main.c",)

#: Deviations of the embedded MHE: OSQP's sources (adopted code), the OSQP workspace wheelload
#: makes re-entrant, the example program (the linked filter's are the KF's, with its prefix).
MHE_DEVIATIONS: tuple[Deviation, ...] = (
    *(
        Deviation(
            rule=rule,
            files=_OSQP,
            where="OSQP's solver sources and headers",
            why="adopted code (MISRA Compliance:2020): OSQP's embedded solver as OSQP's code "
            "generator writes it, not edited here; its conformance is OSQP's",
        )
        for rule in _OSQP_RULES
    ),
    Deviation(
        rule="11.3",
        files=("osqp/wheelload_mhe_workspace.c",),
        where="(LinSysSolver *)&w->linsys in the workspace's initialiser",
        why="OSQP's workspace holds its linear-system solver through OSQP's base type, whose "
        "members begin QDLDL's solver struct (OSQP's own design, kept by the re-entrant copy)",
    ),
    *(
        Deviation(
            rule=rule,
            files=_MHE_MAIN,
            where=where,
            why="host-side example program (input files in, CSV out), not part of the ECU "
            "build, which is libwheelload_mhe.a",
        )
        for rule, where in (
            ("10.3", "the loop flag from a status"),
            ("14.4", "tests of FILE pointers and flags"),
            ("15.6", "one-line loops writing CSV fields"),
            ("17.7", "fprintf's return value unused"),
            ("21.3", "calloc of one state per input file"),
            ("21.6", "reads and writes files with stdio"),
        )
    ),
    *(
        Deviation(
            rule=rule,
            files=("wheelload_mhe_run.c",),
            where=where,
            why="host-side runner of a whole log (the Python binding, the benchmarks) timing "
            "each sample; the estimator (wheelload_mhe.c) needs nothing of it and an ECU build "
            "leaves the file out",
        )
        for rule, where in (
            ("21.1", "#define _POSIX_C_SOURCE: asks the C library for POSIX clock_gettime"),
            ("21.10", "#include <time.h>, clock_gettime of each sample's wall time"),
        )
    ),
)

#: The deviation of an MHE driver whose generated sizes make some of its generic index
#: arithmetic trivial: the hard constraint's one load variable per sample (W = 1, the
#: null-space coordinate), acceleration bias states without travel ones (ND = 0).
TRIVIAL_SIZE_DEVIATIONS: tuple[Deviation, ...] = (
    Deviation(
        rule="2.2",
        files=("wheelload_mhe.c",),
        where="index arithmetic with the window sizes (W * W, 4 * W, c * W + a; NB - ND, ND + c)",
        why="one driver for every window: with the hard constraint W = 1, with acceleration "
        "biases alone ND = 0, and these are multiplications by 1 and additions of 0, folded by "
        "the compiler; the record lists this deviation only for a driver of such sizes",
    ),
)

_HEADER = """# MISRA C:2012 deviations of the generated code

cppcheck's MISRA add-on (`wheelload misra FOLDER`) reports the findings of this folder's C; a
required finding of a rule and file listed here is a deviation, with its reason. Any other
required finding is an error of the generator.

| rule | files | where | why |
| --- | --- | --- | --- |
"""


def deviation_record(deviations: Sequence[Deviation]) -> str:
    """The record's Markdown text."""
    rows = [f"| {d.rule} | {' '.join(d.files)} | {d.where} | {d.why} |" for d in deviations]
    return _HEADER + "\n".join(rows) + "\n"


def write_deviation_record(folder: Path, deviations: Sequence[Deviation], prefix: str) -> Path:
    """Write the record of ``deviations`` (files for ``prefix``) into ``folder``."""
    path = Path(folder) / RECORD_NAME
    write_text(path, deviation_record([d.for_prefix(prefix) for d in deviations]), replace=True)
    return path


def read_deviations(folder: Path) -> tuple[Deviation, ...]:
    """The deviations of the record in ``folder`` (none without a record)."""
    path = Path(folder) / RECORD_NAME
    if not path.is_file():
        return ()
    deviations = []
    for line in path.read_text("utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 4 or cells[0] in ("rule", "---"):
            continue
        rule, files, where, why = cells
        deviations.append(Deviation(rule=rule, files=tuple(files.split()), where=where, why=why))
    return tuple(deviations)
