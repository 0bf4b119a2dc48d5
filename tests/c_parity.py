"""C parity: generate the C, compile it with the project's flags, run or load it, and compare
it with Python to the tolerance the test states (CasADi's own parity test: generate,
compile, load back, compare).

Every test of generated C builds through here:

- the KF's library (``wheelload codegen``): :func:`kf_library`, then :func:`compile_program`
  links a main (the library's example by default) under the project's ``STRICT_CFLAGS``
  (``estimators/codegen/kf.py``: strict warnings as errors, in both precisions);
  :func:`check_codegen` does both, runs the example on a log and compares its loads;
- the embedded MHE: :func:`mhe_library` (gcc -O2 -fPIC, loaded with ctypes) and
  :func:`mhe_program` (its example program);
- a test's own program (a driver of the library's functions, a sanitized build):
  :func:`compile_c`, and :func:`compiler_refusal` to ask first whether the compiler takes
  the flags here.

:func:`header_dependencies` asks the compiler which headers a source reads;
:func:`run_program` runs a built program; :func:`c_estimates` reads the example's CSV;
:func:`assert_c_equals_python` compares, to the ``rtol`` and ``atol`` each test states and
explains (double builds: the same operations as Python's compiled step, to 1e-9 relative;
float builds: about 7 significant digits).
"""

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators.codegen.kf import (
    STRICT_CFLAGS,
    CodegenOptions,
    GeneratedLibrary,
    build_program,
    generate,
)
from wheelload.estimators.codegen.mhe_build import build_mhe_library, build_mhe_program

#: Mark of a test (or module, as ``pytestmark``) that builds C: skipped where gcc is missing.
needs_gcc = pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")


def kf_library(
    vehicle_file: str | Path,
    folder: str | Path,
    options: CodegenOptions | None = None,
    *,
    step=None,
    allow_unusual: bool = False,
) -> GeneratedLibrary:
    """The KF's C library of ``vehicle_file``, written into ``folder`` as ``wheelload
    codegen`` writes it (``step``: a step Function of the test's own; ``allow_unusual``: a
    vehicle outside the physical ranges)."""
    return generate(vehicle_file, Path(folder), options, step, allow_unusual=allow_unusual)


def compile_program(
    library: GeneratedLibrary,
    main_source: Path | None = None,
    name: str = "example",
    *,
    compiler: str = "gcc",
    flags: tuple[str, ...] = STRICT_CFLAGS,
) -> Path:
    """``main_source`` (the library's example program by default) linked with the library
    into ``name`` beside it, compiled by ``compiler`` under ``flags`` (the strict warning
    flags, warnings as errors); a failed build raises with gcc's message."""
    main_source = library.example if main_source is None else main_source
    binary = library.header.parent / name
    return build_program(library, main_source, binary, compiler=compiler, flags=flags)


def kf_program(
    vehicle_file: str | Path,
    folder: str | Path,
    options: CodegenOptions | None = None,
    *,
    allow_unusual: bool = False,
) -> Path:
    """The example program of ``vehicle_file``'s library: :func:`kf_library`, then
    :func:`compile_program` under the strict flags."""
    library = kf_library(vehicle_file, folder, options, allow_unusual=allow_unusual)
    return compile_program(library)


#: The embedded MHE generated into a folder, compiled (gcc -O2 -fPIC) and loaded with ctypes:
#: ``mhe_library(vehicle, settings, folder, dt, precision, vehicle_path=...)``, whose
#: ``run(signals)`` gives the C's estimates (``vehicle_path``: the KF linked in).
mhe_library = build_mhe_library

#: The embedded MHE's example program (one instance per input file), built in a folder:
#: ``mhe_program(vehicle, settings, folder, dt, precision=..., compiler=..., flags=...,
#: vehicle_path=...)`` (a cross compiler too).
mhe_program = build_mhe_program


def compile_c(
    binary: str | Path,
    sources,
    flags: tuple[str, ...],
    *,
    compiler: str = "gcc",
    includes=(),
    libraries=("-lm",),
) -> Path:
    """A test's own program: ``sources`` (C files, objects, static libraries) compiled and
    linked into ``binary`` by ``compiler`` with ``flags``; a failed build fails the test
    with the compiler's message."""
    command = [compiler, *flags, "-o", str(binary), *includes, *map(str, sources), *libraries]
    built = subprocess.run(command, capture_output=True, text=True)
    assert built.returncode == 0, f"{' '.join(command)}:\n{built.stderr[-3000:]}"
    return Path(binary)


def compiler_refusal(
    flags: tuple[str, ...], *, compiler: str = "gcc", binary: str | Path = os.devnull
) -> str | None:
    """None if ``compiler`` builds and links an empty program (into ``binary``) with
    ``flags`` here, else why not (no compiler, or its message): a test then skips, or
    builds without them."""
    if shutil.which(compiler) is None:
        return f"no {compiler}"
    probe = subprocess.run(
        [compiler, *flags, "-x", "c", "-o", str(binary), "-"],
        input="int main(void) { return 0; }\n", capture_output=True, text=True,
    )  # fmt: skip
    if probe.returncode != 0:
        return f"{compiler} cannot build with {' '.join(flags)}: {probe.stderr.strip()[-200:]}"
    return None


def header_dependencies(source: Path, includes=(), *, compiler: str = "gcc") -> set[Path]:
    """The headers ``compiler`` reads when it compiles ``source`` with ``includes``, as it
    reports them itself (``gcc -MM``: the make rule of the object, system headers left out)."""
    done = run_program(compiler, "-MM", *includes, source)
    rule = done.stdout.replace("\\\n", " ").split(":", 1)[1].split()
    return {Path(name).resolve() for name in rule if name.endswith(".h")}


def run_program(binary, *arguments, stdin: str | None = None, env=None, check: bool = True):
    """``binary`` run with ``arguments`` (text in and out, both captured); with ``check`` a
    non-zero exit status fails the test with the program's stderr."""
    done = subprocess.run([str(binary), *map(str, arguments)], input=stdin,
                          capture_output=True, text=True, env=env)  # fmt: skip
    if check:
        assert done.returncode == 0, f"{binary} exited {done.returncode}:\n{done.stderr[-3000:]}"
    return done


def c_estimates(binary, log: Path, out: Path, *overrides: str) -> pd.DataFrame:
    """The example program's estimates of the log file ``log``, written to ``out`` and read
    back (``overrides``: run-time parameters as ``name=value``)."""
    run_program(binary, log, out, *overrides)
    return pd.read_csv(out)


def assert_c_equals_python(c, python, *, rtol: float, atol: float, what: str = "") -> None:
    """The C's values equal Python's to ``rtol`` relative and ``atol`` absolute
    (``numpy.testing.assert_allclose``): the tolerance the calling test states and explains."""
    np.testing.assert_allclose(c, python, rtol=rtol, atol=atol, err_msg=what)


def check_codegen(
    vehicle_file: str | Path,
    folder: str | Path,
    log: Path,
    expected,
    *,
    columns,
    rtol: float,
    atol: float,
    options: CodegenOptions | None = None,
    allow_unusual: bool = False,
) -> pd.DataFrame:
    """Generate ``vehicle_file``'s library into ``folder``, compile its example under the
    strict flags, run it on ``log`` and check its ``columns`` against ``expected`` (Python's
    values, in the same order) to ``rtol`` and ``atol``; returns the C's estimates."""
    binary = kf_program(vehicle_file, folder, options, allow_unusual=allow_unusual)
    c = c_estimates(binary, log, Path(folder) / "estimates.csv")
    assert_c_equals_python(c[list(columns)], expected, rtol=rtol, atol=atol, what=str(log))
    return c


def lane_change_logs(folder: Path, gaps) -> dict[str, tuple[Path, pd.DataFrame]]:
    """The plant's ISO lane change written as CSV in ``folder``, clean and with ``gaps``
    (``(column, first row, last row)`` set to NaN): ``{"clean" | "gaps": (path, frame)}``."""
    from wheelload.models import example_vehicle_path
    from wheelload.studies.drive.scenario_runner import run_scenario

    frame = run_scenario("iso-dlc", example_vehicle_path()).log
    holed = frame.copy()
    for column, first, last in gaps:
        holed.loc[first:last, column] = np.nan
    logs = {}
    for name, table in (("clean", frame), ("gaps", holed)):
        path = folder / f"{name}.csv"
        table.to_csv(path, index=False, float_format="%.17g")
        logs[name] = (path, table)
    return logs
