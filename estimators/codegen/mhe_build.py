r"""The embedded MHE compiled and run: a shared library over a log, a stand-alone program.

:func:`build_mhe_library` generates the C (:func:`~wheelload.estimators.codegen.mhe.generate_mhe`),
compiles it with gcc -O2 and loads it with ctypes (:class:`CompiledMhe`);
:func:`build_mhe_program` builds the stand-alone example program, which reads input rows from
text files, one estimator instance per file (any compiler, e.g. ``arm-linux-gnueabihf-gcc
-static``); :func:`write_inputs` writes them.

Example
-------
>>> library = build_mhe_library(vehicle, MheSettings(horizon=20), Path("build"), dt=0.01,
...                             vehicle_path=Path("car.toml"))
>>> result = library.run(signals)
"""

from __future__ import annotations

import ctypes
import re
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wheelload.estimators.codegen.mhe import (
    EXAMPLE,
    TEMPLATES,
    generate_mhe,
    include_directories,
    mhe_includes,
    mhe_sources,
    relative_includes,
)
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import DEFAULT_RATE_FILTER, RateDerivativeFilter
from wheelload.estimators.mhe.settings import MheSettings
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.types import Signals
from wheelload.models import Vehicle
from wheelload.models.runtime.build_folder import cached_object


@dataclass(frozen=True)
class EmbeddedResult:
    """The embedded MHE's outputs over a log, row k from sample k (the estimate of k - lag)."""

    loads: np.ndarray  # (n, 4) N
    std: np.ndarray  # (n, 4) N, the fallback filter's (0 without one)
    residual: np.ndarray  # (n, 3) b - A x
    bias: np.ndarray  # (n, nb) travel offsets [m], then ax, ay [m/s^2]
    status: np.ndarray  # (n,) OSQP status value
    flags: np.ndarray  # (n,) StepFlag bits of the skipped updates
    iterations: np.ndarray  # (n,)
    fallback: np.ndarray  # (n,) bool
    solve_time: np.ndarray  # (n,) s


class CompiledMhe:
    """The generated embedded MHE compiled to a shared library and loaded with ctypes.

    Each :meth:`run` has a state of its own (``wheelload_mhe_state``, allocated here at
    ``wheelload_mhe_state_size()`` bytes and reset by ``wheelload_mhe_run``).
    """

    def __init__(self, path: Path, n_bias: int) -> None:
        self._lib = ctypes.CDLL(str(path))
        self._lib.wheelload_mhe_run.restype = None
        self._lib.wheelload_mhe_state_size.restype = ctypes.c_size_t
        self.n_bias = n_bias

    @property
    def state_size(self) -> int:
        """Bytes of one instance's state, ``sizeof(wheelload_mhe_state)``."""
        return int(self._lib.wheelload_mhe_state_size())

    def run(
        self, signals: Signals, rate_filter: RateDerivativeFilter = DEFAULT_RATE_FILTER
    ) -> EmbeddedResult:
        """The log through the C MHE (the body-rate derivatives, where not logged, from
        ``rate_filter``: a vehicle file's is ``RateDerivativeFilter.of(vehicle)``)."""
        u = np.ascontiguousarray(input_matrix(signals, rate_filter).T, dtype=float)
        dt = np.ascontiguousarray(sample_intervals(signals.t), dtype=float)
        n = len(signals)
        out = dict(
            loads=np.zeros((n, 4)), std=np.zeros((n, 4)), residual=np.zeros((n, 3)),
            bias=np.zeros((n, self.n_bias)), status=np.zeros(n, dtype=np.int32),
            iterations=np.zeros(n, dtype=np.int32), fallback=np.zeros(n, dtype=np.int32),
            flags=np.zeros(n, dtype=np.uint32), solve_time=np.zeros(n),
        )  # fmt: skip
        kinds = dict(status=ctypes.c_int, iterations=ctypes.c_int, fallback=ctypes.c_int,
                     flags=ctypes.c_uint)  # fmt: skip
        names = ["loads", "std", "residual", "bias", "status", "iterations", "fallback",
                 "flags", "solve_time"]  # fmt: skip
        pointers = [
            out[name].ctypes.data_as(ctypes.POINTER(kinds.get(name, ctypes.c_double)))
            for name in names
        ]
        # Doubles: aligned for every member of the state (doubles, pointers, OSQPInt).
        state = np.zeros(-(-self.state_size // 8), dtype=np.float64)
        self._lib.wheelload_mhe_run(
            state.ctypes.data_as(ctypes.c_void_p),
            ctypes.c_int(n),
            u.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            dt.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            *pointers,
        )
        out["flags"] = out["flags"].astype(np.int64)
        out["fallback"] = out["fallback"].astype(bool)
        return EmbeddedResult(**out)


def build_mhe_library(
    vehicle: Vehicle,
    settings: MheSettings,
    folder: Path,
    dt: float,
    precision: Precision = Precision.DOUBLE,
    *,
    vehicle_path: Path | None = None,
) -> CompiledMhe:
    """Generate, compile with gcc -O2 into ``folder/libwheelload_mhe.so`` and load.

    ``vehicle_path``: link the KF in (see :func:`generate_mhe`).
    """
    folder = generate_mhe(vehicle, settings, Path(folder), dt, precision,
                          vehicle_path=vehicle_path)  # fmt: skip
    library = folder / "libwheelload_mhe.so"
    flags = ("-O2", "-fPIC", "-std=gnu99")
    command = ["gcc", *flags, "-shared", "-o", str(library), *mhe_includes(folder),
               *compiled_sources(folder, ("gcc", *flags)), "-lm"]  # fmt: skip
    completed = subprocess.run(command, capture_output=True, text=True)
    if completed.returncode != 0:
        raise RuntimeError(f"compiling the embedded MHE failed:\n{completed.stderr[-3000:]}")
    return CompiledMhe(library, n_bias(folder))


def compiled_sources(folder: Path, command: tuple[str, ...]) -> list[str]:
    """The embedded MHE's C files for ``command`` as objects each compiled once per text, the
    headers it includes and ``command`` (``cached_object``): the linked KF, OSQP's sources
    and a window built again (another test, another run) are not compiled again."""
    directories = include_directories(folder)
    command = (*command, *relative_includes(folder))
    return [str(cached_object(path, included_headers(path, directories), command, root=folder))
            for path in mhe_sources(folder)]  # fmt: skip


def included_headers(source: Path, directories: list[Path]) -> tuple[Path, ...]:
    """Every header ``source`` includes with ``#include "..."``, directly or through another,
    found beside the including file or in ``directories`` (gcc's order for ``-I``); the
    others (``<...>``, not found) are the system's."""
    found: dict[Path, None] = {}
    pending = [source]
    while pending:
        current = pending.pop()
        for match in _INCLUDE.finditer(current.read_text()):
            for directory in (current.parent, *directories):
                header = directory / match.group(1)
                if header.is_file():
                    if header not in found and header != source:
                        found[header] = None
                        pending.append(header)
                    break
    return tuple(sorted(found))


_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)


def n_bias(folder: Path) -> int:
    """WHEELLOAD_MHE_N_BIAS of a generated embedded MHE."""
    for line in (Path(folder) / "wheelload_mhe.h").read_text().splitlines():
        if line.startswith("#define WHEELLOAD_MHE_N_BIAS "):
            return int(line.split()[2])
    raise ValueError(f"{folder}: not a generated embedded MHE (no wheelload_mhe.h)")


#: The example program (``templates/mhe_main.c``, written beside the library by
#: :func:`~wheelload.estimators.codegen.mhe.generate_mhe` as ``wheelload_mhe_main.c``): one
#: instance per input file, interleaved.
MAIN = (TEMPLATES / "mhe_main.c").read_text()


def build_mhe_program(
    vehicle: Vehicle,
    settings: MheSettings,
    folder: Path,
    dt: float,
    *,
    precision: Precision = Precision.DOUBLE,
    compiler: str = "gcc",
    flags: tuple[str, ...] = ("-O2",),
    vehicle_path: Path | None = None,
) -> Path:
    """Generate the embedded MHE and compile its example program (:data:`MAIN`, one instance
    per input file) into ``folder/wheelload_mhe``.

    ``compiler`` may be a cross compiler (e.g. ``arm-linux-gnueabihf-gcc`` with
    ``-static`` among ``flags``, run under ``qemu-arm``).
    """
    folder = generate_mhe(vehicle, settings, Path(folder), dt, precision,
                          vehicle_path=vehicle_path)  # fmt: skip
    main = folder / EXAMPLE
    binary = folder / "wheelload_mhe"
    sources = compiled_sources(folder, (compiler, *flags, "-std=gnu99"))
    command = [compiler, *flags, "-std=gnu99", "-o", str(binary), *mhe_includes(folder),
               str(main), *sources, "-lm"]  # fmt: skip
    completed = subprocess.run(command, capture_output=True, text=True)
    if completed.returncode != 0:
        raise RuntimeError(f"compiling the embedded MHE failed:\n{completed.stderr[-3000:]}")
    return binary


def write_inputs(
    signals: Signals, path: Path, rate_filter: RateDerivativeFilter = DEFAULT_RATE_FILTER
) -> Path:
    """The log's intervals and inputs as text rows for :data:`MAIN` (17 digits, 'nan' missing;
    ``rate_filter`` as :meth:`EmbeddedMhe.run`)."""
    rows = np.column_stack([sample_intervals(signals.t), input_matrix(signals, rate_filter).T])
    np.savetxt(path, rows, fmt="%.17g")
    return path
