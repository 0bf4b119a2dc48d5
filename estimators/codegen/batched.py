"""Many logs through the generated library's batched step, side by side.

:func:`run_batched` filters several logs (or Monte Carlo trials) at once:
the two-stage KF's C library is generated from the filter's own step
Function (:mod:`wheelload.estimators.codegen.kf`, runtime parameters, double),
built once per model structure with the Makefile's ``FAST_CFLAGS`` (cached in the
private build folder by its text and flags, and found again through a record under
:func:`~wheelload.estimators.codegen.structure.structure_key` without generating it: an
edit of the vehicle file's values reuses the build, the values are set through the
parameter struct before each run) and stepped ``n`` filters at a
time through ``wheelload_batch_step_batch`` (struct of arrays, vectorised
across the filters). One C call runs a whole batch of logs: the driver
reads each log's own arrays in place (channel by channel, with their
strides; intervals from the time stamps), writes its outputs in place, ORs in
the flags of inputs the log lacks and notes which logs had an isolated fault
(the fault records are made for those only): no per-sample Python, no input
matrix, no copies. Logs of different lengths are padded with rejected samples
(the state is held) whose outputs are not written; the logs of a batch are
taken longest first, so the padding is small. Logs are grouped by their nominal
interval, which sets the measurement noise.

Each log's :class:`Estimate` equals :meth:`TwoStageKF.run` on it to about
1e-12 relative (the same operations; FMA contraction rounds once where
``run`` rounds twice), flag for flag.

Example
-------
>>> estimates = run_batched(TwoStageKF(vehicle), "car.toml", [log_a, log_b, log_c])
"""

from __future__ import annotations

import ctypes
import functools
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from wheelload.estimators.codegen.kf import FAST_CFLAGS, PACKED, CodegenOptions, generate
from wheelload.estimators.codegen.structure import structure_key
from wheelload.estimators.guards.settings import FAULT_CHANNELS
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.kf.tuning import nominal_interval
from wheelload.estimators.kf.two_stage import TwoStageKF, sensor_faults
from wheelload.estimators.logs.inputs import input_blocks
from wheelload.estimators.logs.output_files import write_text
from wheelload.estimators.logs.signals import RateDerivativeFilter
from wheelload.estimators.result import Estimate
from wheelload.estimators.types import Signals, input_bits
from wheelload.models import INPUTS, load_vehicle
from wheelload.models.runtime.build_folder import build_folder, checked_library, shared_library

PREFIX = "wheelload_batch"
#: The fast build of the library as a shared object: ``FAST_CFLAGS``, its warnings reported
#: but not errors here, with gcc's report of the loops it vectorised; both are kept beside
#: the library (``build_report``), so one compile serves the run and the check of the build.
KERNEL_FLAGS = (
    "gcc",
    *(flag for flag in FAST_CFLAGS if flag != "-Werror"),
    "-fopt-info-vec-optimized",
    "-fPIC",
    "-shared",
)
#: The driver's build: ``FAST_CFLAGS`` without the warnings.
SHARED_FLAGS = (
    "gcc",
    *(flag for flag in FAST_CFLAGS if not flag.startswith("-W")),
    "-fPIC",
    "-shared",
)

DRIVER = """
#include <math.h>
#include <string.h>

#define MAX_FILTERS ${max_filters}
#define BLOCK 16

typedef void (*step_batch_fn)(const ${prefix}_batch *, const ${prefix}_params *,
                              const ${prefix}_real *, const ${prefix}_real *,
                              const ${prefix}_batch_output *);
typedef ${prefix}_real *(*param_field_fn)(${prefix}_params *, int);

/* n (<= MAX_FILTERS) logs side by side over `steps` samples, through the library's
   batched step `step` (its ${prefix}_step_batch) with the calibration `values` (one per
   field of ${prefix}_param_names, set through `field` on a copy of `defaults`).

   Log b's channel k (order of ${prefix}_input_names) is read in place from the log's
   own arrays: sample i at channels[b * N_INPUTS + k][i * strides[b * N_INPUTS + k]], a
   null pointer for a channel the log lacks (NaN); its intervals come from its time
   stamps times[b] (the first sample reuses the first interval). Its outputs are rows
   of [lengths[b]][4] loads and std, [..][3] residual, [..][N_FAULT_CHANNELS]
   statistic, faults and flags (input_bits[b] or'ed in); any_fault[b] is the OR of its
   fault bits. Past its end a filter is fed a rejected sample (dt NaN: the state is
   held) and nothing is written. The state x, P, monitor ([rows][n]) is carried in
   place. */
void ${prefix}_run_batch(step_batch_fn step, param_field_fn field,
                         const ${prefix}_params *defaults, int n, long steps,
                         const double *values, const double *const *channels,
                         const long *strides, const double *const *times,
                         const long *lengths, const int64_t *input_bits, double *x, double *P,
                         double *monitor, double *const *loads, double *const *stds,
                         double *const *residuals, double *const *statistics,
                         uint32_t *const *faults, int64_t *const *flags, uint32_t *any_fault)
{
    /* on the stack: concurrent calls from threads are independent. Inputs and
       outputs go through blocks of BLOCK steps so that each log's rows are read
       and written in runs (the logs' arrays are many separate streams). */
    double u[BLOCK][${PREFIX}_N_INPUTS * MAX_FILTERS], dt[BLOCK][MAX_FILTERS];
    double state_x[BLOCK][4 * MAX_FILTERS], std[BLOCK][4 * MAX_FILTERS];
    double residual[BLOCK][3 * MAX_FILTERS];
    double statistic[BLOCK][${PREFIX}_N_FAULT_CHANNELS * MAX_FILTERS];
    uint32_t fault_bits[BLOCK][MAX_FILTERS], flag_bits[BLOCK][MAX_FILTERS];
    ${prefix}_batch batch;
    ${prefix}_params params = *defaults;
    long t0, t;
    int b, k, j, m;
    for (k = 0; k < ${PREFIX}_N_PARAMS; ++k) {
        *field(&params, k) = values[k];
    }
    batch.n = n;
    batch.x = x;
    batch.P = P;
    batch.monitor = monitor;
    for (b = 0; b < n; ++b) {
        any_fault[b] = 0u;
    }
    for (t0 = 0; t0 < steps; t0 += BLOCK) {
        m = steps - t0 < BLOCK ? (int)(steps - t0) : BLOCK;
        for (b = 0; b < n; ++b) {
            const long length = lengths[b], live = length - t0; /* steps left in the block */
            const double *time = times[b];
            for (k = 0; k < ${PREFIX}_N_INPUTS; ++k) {
                const double *column = channels[b * ${PREFIX}_N_INPUTS + k];
                const long stride = strides[b * ${PREFIX}_N_INPUTS + k];
                if (column == 0) {
                    for (j = 0; j < m; ++j) {
                        u[j][k * n + b] = (double)NAN;
                    }
                    continue;
                }
                column += t0 * stride;
                for (j = 0; j < m; ++j) {
                    u[j][k * n + b] = j < live ? column[j * stride] : 0.0;
                }
            }
            for (j = 0; j < m; ++j) {
                t = t0 + j;
                dt[j][b] = (t >= length || length < 2) ? (double)NAN
                           : t == 0                    ? time[1] - time[0]
                                                       : time[t] - time[t - 1];
            }
        }
        for (j = 0; j < m; ++j) {
            ${prefix}_batch_output output;
            output.std = std[j];
            output.residual = residual[j];
            output.fault_statistic = statistic[j];
            output.faults = fault_bits[j];
            output.flags = flag_bits[j];
            step(&batch, &params, u[j], dt[j], &output);
            memcpy(state_x[j], x, sizeof(double) * 4 * (size_t)n);
        }
        for (b = 0; b < n; ++b) {
            const long live = lengths[b] - t0;
            uint32_t seen = 0u;
            for (j = 0; j < m && j < live; ++j) {
                t = t0 + j;
                for (k = 0; k < 4; ++k) {
                    loads[b][t * 4 + k] = state_x[j][k * n + b];
                    stds[b][t * 4 + k] = std[j][k * n + b];
                }
                for (k = 0; k < 3; ++k) {
                    residuals[b][t * 3 + k] = residual[j][k * n + b];
                }
                for (k = 0; k < ${PREFIX}_N_FAULT_CHANNELS; ++k) {
                    statistics[b][t * ${PREFIX}_N_FAULT_CHANNELS + k] = statistic[j][k * n + b];
                }
                faults[b][t] = fault_bits[j][b];
                flags[b][t] = (int64_t)flag_bits[j][b] | input_bits[b];
                seen |= fault_bits[j][b];
            }
            any_fault[b] |= seen;
        }
    }
}
"""
#: Filters side by side at most per call (the driver's buffers).
MAX_FILTERS = 64
#: A batch is padded to a multiple of this many filters (8 doubles: an AVX-512 vector, two
#: AVX2 vectors): no filter falls into a scalar remainder loop.
LANES = 8


@dataclass(frozen=True)
class BatchLibrary:
    """The generated library (its batched step) and the driver that feeds it logs.

    Two shared objects: the library alone (the kernel, the slow build) and the small driver,
    which reaches the library's batched step, parameter fields and default calibration
    through pointers (so the self-test can be linked against the very same kernel). Both
    are found through the record of their model structure (:func:`batch_library`).
    ``source`` is the kernel's C text as compiled (the header in place of its
    ``#include``), kept beside it.
    """

    kernel: ctypes.CDLL
    driver: ctypes.CDLL

    @property
    def path(self) -> Path:
        """The library's shared object (the kernel)."""
        return Path(self.kernel._name)

    @property
    def source(self) -> str:
        """The kernel's C text as compiled (:func:`source_path`)."""
        return source_path(self.path).read_text()

    def symbol(self, name: str) -> ctypes.c_void_p:
        """Address of ``wheelload_batch_<name>`` in the library (function or constant)."""
        return ctypes.c_void_p(
            ctypes.addressof(ctypes.c_char.in_dll(self.kernel, f"{PREFIX}_{name}"))
        )


def source_path(library: Path) -> Path:
    """Where the C text a batch library was compiled from is kept: ``<library>.c``."""
    return library.with_name(library.name + ".c")


#: The generator's options of the batch library (double, runtime parameters, its prefix).
OPTIONS = CodegenOptions(precision=Precision.DOUBLE, prefix=PREFIX)


def batch_library(step: ca.Function, vehicle_path: Path) -> BatchLibrary:
    """The generated library for ``step`` and the batch driver, built once per model
    structure and loaded.

    The C is the same for every vehicle file of one structure (:func:`structure_key`: the
    step, the options, the file's switches and sections; not its numbers, texts or
    comments): the calibration is set at run time through the parameter struct
    (:func:`run_batched`), so an edit of the file's values loads the library built before.
    A first build of a structure is announced on stderr when it takes long.
    """
    vehicle = load_vehicle(vehicle_path, allow_unusual=True)
    return _library(step, structure_key(step, vehicle, OPTIONS), Path(vehicle_path))


@functools.lru_cache(maxsize=4)
def _library(step: ca.Function, key: str, vehicle_path: Path) -> BatchLibrary:
    """:func:`batch_library` of the structure ``key``: the libraries its record names
    (:func:`structure_record`), or those of the C generated from ``vehicle_path``.

    The generated C is compiled only when its text is new (``shared_library``, cached by the
    text and flags): a structure met for the first time after an edit of the package's code
    that leaves the C as it was (or with a vehicle file built before) loads its build.
    """
    record = structure_record(key)
    names = _recorded(record)
    if names is not None:
        library = BatchLibrary(kernel=ctypes.CDLL(str(names[0])), driver=ctypes.CDLL(str(names[1])))
    else:
        sources = library_sources(step, vehicle_path)
        what = f"the many-logs library (model structure {key[:12]})"
        why = "first build of this model structure; edits of the vehicle file's values reuse it"
        kernel = shared_library(sources["kernel"], PREFIX, KERNEL_FLAGS, what=what, why=why)
        driver = shared_library(
            sources["driver"], f"{PREFIX}_driver", SHARED_FLAGS, what=f"its driver ({key[:12]})"
        )
        library = BatchLibrary(kernel=kernel, driver=driver)
        kept = source_path(library.path)
        if not kept.exists():
            write_text(kept, sources["kernel"], replace=True)
        write_text(record, f"{library.path.name}\n{Path(driver._name).name}\n", replace=True)
    getattr(library.driver, f"{PREFIX}_run_batch").restype = None
    return library


def structure_record(key: str) -> Path:
    """The build folder's record of the libraries built for the model structure ``key``
    (their file names, kernel then driver)."""
    return build_folder() / f"{PREFIX}_{key[:32]}.structure"


def _recorded(record: Path) -> tuple[Path, Path] | None:
    """The kernel and driver ``record`` names, when both are in place and match their build
    records (:func:`checked_library`); None otherwise (they are built or found again)."""
    try:
        names = record.read_text().split()
    except OSError:
        return None
    paths = tuple(build_folder() / name for name in names)
    if len(paths) != 2 or any(checked_library(path) is not None for path in paths):
        return None
    return paths[0], paths[1]


def library_sources(step: ca.Function, vehicle_path: Path) -> dict[str, str]:
    """The kernel's C (header in place) and the driver's (header and driver) for the vehicle
    file (copied under one name, ``vehicle.toml``: the text does not depend on its name)."""
    with tempfile.TemporaryDirectory(dir=build_folder()) as folder:
        vehicle = Path(folder) / "vehicle.toml"
        vehicle.write_bytes(Path(vehicle_path).read_bytes())
        library = generate(vehicle, Path(folder) / "c", OPTIONS, step, allow_unusual=True)
        header = library.header.read_text()
        source = library.source.read_text().replace(f'#include "{PREFIX}.h"', header, 1)
    driver = (
        DRIVER.replace("${prefix}", PREFIX)
        .replace("${PREFIX}", PREFIX.upper())
        .replace("${max_filters}", str(MAX_FILTERS))
    )
    return {"kernel": source, "driver": header + driver}


def _pointer(array: np.ndarray) -> ctypes.c_void_p:
    return ctypes.c_void_p(array.ctypes.data)


def _pointers(arrays: list[np.ndarray], n: int) -> ctypes.Array:
    """The arrays' addresses, null pointers after them up to ``n``."""
    return (ctypes.c_void_p * n)(*[array.ctypes.data for array in arrays])


def _channels(
    logs: list[Signals], n: int, keep: list, rate_filter: RateDerivativeFilter
) -> tuple[ctypes.Array, np.ndarray]:
    """Each log's input channels as (address, stride in samples), read in place (the
    body-rate derivatives, where not logged, from ``rate_filter``).

    Address 0 where the log lacks the channel, and for the filters after the logs up
    to ``n``. An array that is not float64 with strides of whole doubles is copied
    (and kept alive in ``keep``).
    """
    addresses, strides = [], []
    for log in logs:
        for values, width in input_blocks(log, rate_filter):
            if values is None:
                addresses += [0] * width
                strides += [0] * width
                continue
            if values.dtype != np.float64 or any(s < 0 or s % 8 for s in values.strides):
                values = np.ascontiguousarray(values, dtype=np.float64)
            keep.append(values)
            row, column = values.strides
            addresses += [values.ctypes.data + k * column for k in range(width)]
            strides += [row // 8] * width
    if len(addresses) != len(INPUTS) * len(logs):
        raise RuntimeError(f"{len(addresses)} input channels for {len(logs)} logs")
    addresses += [0] * (len(INPUTS) * (n - len(logs)))
    strides += [0] * (len(INPUTS) * (n - len(logs)))
    return (ctypes.c_void_p * len(addresses))(*addresses), np.array(strides, dtype=np.int64)


def run_batched(
    kf: TwoStageKF, vehicle_path: str | Path, logs: Sequence[Signals]
) -> list[Estimate]:
    """:meth:`TwoStageKF.run` of each log, the logs stepped side by side in C.

    ``vehicle_path`` is the vehicle file ``kf`` was built from (it names the
    generated library; the parameters themselves are ``kf``'s). Logs of one nominal
    interval go through the driver longest first, at most :data:`MAX_FILTERS` per call,
    so that a batch holds logs of about one length (little padding).
    """
    if not logs:
        return []
    return run_on_library(batch_library(kf.step_function, Path(vehicle_path)), kf, logs)


def run_on_library(
    library: BatchLibrary, kf: TwoStageKF, logs: Sequence[Signals]
) -> list[Estimate]:
    """:func:`run_batched` through a given build of the library (one for ``kf``'s step and
    a vehicle file of its structure), ``kf``'s values set at run time."""
    estimates: dict[int, Estimate] = {}
    groups: dict[float, list[int]] = {}
    for index, log in enumerate(logs):
        groups.setdefault(kf.sample_interval or nominal_interval(log.t), []).append(index)
    for interval, members in groups.items():
        members.sort(key=lambda i: -len(logs[i]))
        calls = -(-len(members) // MAX_FILTERS)
        size = -(-len(members) // calls)
        for start in range(0, len(members), size):
            chunk = members[start : start + size]
            batch = [logs[i] for i in chunk]
            for i, estimate in zip(chunk, _run_group(library, kf, interval, batch), strict=True):
                estimates[i] = estimate
    return [estimates[i] for i in range(len(logs))]


def _run_group(
    library: BatchLibrary, kf: TwoStageKF, interval: float, logs: list[Signals]
) -> list[Estimate]:
    """Logs with the same nominal interval, stepped side by side (at most MAX_FILTERS)."""
    # Padded with empty filters (length 0: every step rejected, nothing read or written) to
    # a multiple of LANES, so that every log goes through the vectorised loop body: a log's
    # bits do not depend on its batch (a scalar remainder loop may contract FMAs otherwise).
    count = len(logs)
    n = -(-count // LANES) * LANES
    lengths = np.zeros(n, dtype=np.int64)
    lengths[:count] = [len(log) for log in logs]
    initial = kf.initial_state()
    params = np.concatenate([kf.p, kf.tuning_for(interval), [kf.vehicle.filter.initial_std]])
    x = np.repeat(initial.x[:, None], n, axis=1)
    P = np.repeat(np.array([initial.P[i, j] for i, j in PACKED])[:, None], n, axis=1)
    monitor = np.repeat(initial.m[:, None], n, axis=1)
    keep: list[np.ndarray] = []
    channels, strides = _channels(logs, n, keep, RateDerivativeFilter.of(kf.vehicle))
    times = [np.ascontiguousarray(log.t, dtype=np.float64) for log in logs]
    bits = np.zeros(n, np.int64)
    bits[:count] = [input_bits(log.az_assumed, log.speed_source) for log in logs]
    n_faults = len(FAULT_CHANNELS)
    lengths_of = lengths[:count]
    loads = [np.empty((length, 4)) for length in lengths_of]
    std = [np.empty((length, 4)) for length in lengths_of]
    residual = [np.empty((length, 3)) for length in lengths_of]
    statistic = [np.empty((length, n_faults)) for length in lengths_of]
    faults = [np.empty(length, np.uint32) for length in lengths_of]
    flags = [np.empty(length, np.int64) for length in lengths_of]
    any_fault = np.empty(n, np.uint32)
    getattr(library.driver, f"{PREFIX}_run_batch")(
        library.symbol("step_batch"),
        library.symbol("param_field"),
        library.symbol("default_params"),
        ctypes.c_int(n),
        ctypes.c_long(int(lengths.max())),
        _pointer(params),
        channels,
        _pointer(strides),
        _pointers(times, n),
        _pointer(lengths),
        _pointer(bits),
        _pointer(x),
        _pointer(P),
        _pointer(monitor),
        _pointers(loads, n),
        _pointers(std, n),
        _pointers(residual, n),
        _pointers(statistic, n),
        _pointers(faults, n),
        _pointers(flags, n),
        _pointer(any_fault),
    )
    estimates = []
    for b, log in enumerate(logs):
        isolated: tuple = ()
        if any_fault[b]:  # the records only for a log with an isolated fault
            fault = ((faults[b][:, None] >> np.arange(n_faults)) & 1).astype(float)
            isolated = sensor_faults(log.t, fault, statistic[b])
        estimates.append(
            Estimate(
                t=log.t.copy(),
                loads=loads[b],
                std=std[b],
                residual=residual[b],
                flags=flags[b],
                sensor_faults=isolated,
            )
        )
    return estimates
