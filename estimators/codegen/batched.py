"""Many logs through the generated library's batched step, side by side.

:func:`run_batched` filters several logs (or Monte Carlo trials) at once:
the two-stage KF's C library is generated from the filter's own step
Function (:mod:`wheelload.estimators.codegen.kf`, runtime parameters, double),
built once with the Makefile's ``FAST_CFLAGS`` (cached in the private build
folder by the hash of its source and flags) and stepped ``n`` filters at a
time through ``wheelload_batch_step_batch`` (struct of arrays, vectorised
across the filters). Logs of different lengths are padded with rejected
samples (the state is held) whose outputs are not written; the C driver
reads each log's input matrix and writes its outputs in place (no padded or
transposed copies); logs are grouped by
their nominal interval, which sets the measurement noise.

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
from pathlib import Path

import casadi as ca
import numpy as np

from wheelload.estimators.codegen.c_emitter import Precision
from wheelload.estimators.codegen.kf import FAST_CFLAGS, PACKED, CodegenOptions, generate
from wheelload.estimators.kf.guard import FAULT_CHANNELS
from wheelload.estimators.kf.tuning import nominal_interval
from wheelload.estimators.kf.two_stage import TwoStageKF, sensor_faults
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import Signals
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.result import Estimate
from wheelload.models.files.build_folder import build_folder, shared_library

PREFIX = "wheelload_batch"
#: The fast build of the library as a shared object (warnings are not errors here).
SHARED_FLAGS = (
    "gcc",
    *(flag for flag in FAST_CFLAGS if not flag.startswith("-W")),
    "-fPIC",
    "-shared",
)

DRIVER = """
#include <string.h>

#define MAX_FILTERS ${max_filters}
#define BLOCK 16

/* n (<= MAX_FILTERS) logs side by side over `steps` samples. Log b: inputs[b] is its
   [N_INPUTS][lengths[b]] matrix (row k = channel k), dts[b] its intervals; its
   outputs are rows of [lengths[b]][4] loads and std, [..][3] residual,
   [..][N_FAULT_CHANNELS] statistic, faults, flags. Past its end a filter is
   fed a rejected sample (dt NaN: the state is held) and nothing is written. The
   state x, P, monitor ([rows][n]) is carried in place. values: the calibration, one
   per field of ${prefix}_param_names (the Python filter's: its derived parameters
   already follow their sources). */
void ${prefix}_run_batch(int n, long steps, const double *values,
                         const double *const *inputs, const long *lengths,
                         const double *const *dts, double *x, double *P, double *monitor,
                         double *const *loads, double *const *stds,
                         double *const *residuals, double *const *statistics,
                         uint32_t *const *faults, uint32_t *const *flags)
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
    ${prefix}_params params = ${prefix}_default_params;
    long t0, t;
    int b, k, j, m;
    for (k = 0; k < ${PREFIX}_N_PARAMS; ++k) {
        *${prefix}_param_field(&params, k) = values[k];
    }
    batch.n = n;
    batch.x = x;
    batch.P = P;
    batch.monitor = monitor;
    for (t0 = 0; t0 < steps; t0 += BLOCK) {
        m = steps - t0 < BLOCK ? (int)(steps - t0) : BLOCK;
        for (b = 0; b < n; ++b) {
            const long live = lengths[b] - t0; /* steps of log b left in this block */
            for (k = 0; k < ${PREFIX}_N_INPUTS; ++k) {
                const double *row = inputs[b] + k * lengths[b] + t0;
                for (j = 0; j < m; ++j) {
                    u[j][k * n + b] = j < live ? row[j] : 0.0;
                }
            }
            for (j = 0; j < m; ++j) {
                dt[j][b] = j < live ? dts[b][t0 + j] : (double)NAN;
            }
        }
        for (j = 0; j < m; ++j) {
            ${prefix}_batch_output output;
            output.std = std[j];
            output.residual = residual[j];
            output.fault_statistic = statistic[j];
            output.faults = fault_bits[j];
            output.flags = flag_bits[j];
            ${prefix}_step_batch(&batch, &params, u[j], dt[j], &output);
            memcpy(state_x[j], x, sizeof(double) * 4 * (size_t)n);
        }
        for (b = 0; b < n; ++b) {
            const long live = lengths[b] - t0;
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
                flags[b][t] = flag_bits[j][b];
            }
        }
    }
}
"""
#: Filters side by side at most per call (the driver's buffers).
MAX_FILTERS = 64


@functools.lru_cache(maxsize=4)
def _library(step: ca.Function, vehicle_path: Path) -> ctypes.CDLL:
    """The generated library for ``step`` with the batch driver, built and loaded."""
    options = CodegenOptions(precision=Precision.DOUBLE, prefix=PREFIX)
    with tempfile.TemporaryDirectory(dir=build_folder()) as folder:
        library = generate(vehicle_path, folder, options, step, allow_unusual=True)
        header = library.header.read_text()
        source = library.source.read_text().replace(f'#include "{PREFIX}.h"', header, 1)
    driver = (
        DRIVER.replace("${prefix}", PREFIX)
        .replace("${PREFIX}", PREFIX.upper())
        .replace("${max_filters}", str(MAX_FILTERS))
    )
    shared = shared_library(source + driver, PREFIX, SHARED_FLAGS)
    function = getattr(shared, f"{PREFIX}_run_batch")
    function.restype = None
    return shared


def _pointer(array: np.ndarray) -> ctypes.c_void_p:
    return ctypes.c_void_p(array.ctypes.data)


def _pointers(arrays: list[np.ndarray]) -> ctypes.Array:
    return (ctypes.c_void_p * len(arrays))(*[array.ctypes.data for array in arrays])


def run_batched(
    kf: TwoStageKF, vehicle_path: str | Path, logs: Sequence[Signals]
) -> list[Estimate]:
    """:meth:`TwoStageKF.run` of each log, the logs stepped side by side in C.

    ``vehicle_path`` is the vehicle file ``kf`` was built from (it names the
    generated library; the parameters themselves are ``kf``'s).
    """
    if not logs:
        return []
    library = _library(kf.step_function, Path(vehicle_path))
    estimates: dict[int, Estimate] = {}
    groups: dict[float, list[int]] = {}
    for index, log in enumerate(logs):
        groups.setdefault(kf.sample_interval or nominal_interval(log.t), []).append(index)
    for interval, members in groups.items():
        batch = [logs[i] for i in members]
        for i, estimate in zip(members, _run_group(library, kf, interval, batch), strict=True):
            estimates[i] = estimate
    return [estimates[i] for i in range(len(logs))]


def _run_group(
    library: ctypes.CDLL, kf: TwoStageKF, interval: float, logs: list[Signals]
) -> list[Estimate]:
    """Logs with the same nominal interval, stepped side by side (at most MAX_FILTERS)."""
    if len(logs) > MAX_FILTERS:
        half = len(logs) // 2
        return _run_group(library, kf, interval, logs[:half]) + _run_group(
            library, kf, interval, logs[half:]
        )
    n, lengths = len(logs), np.array([len(log) for log in logs], dtype=np.int64)
    initial = kf.initial_state()
    params = np.concatenate([kf.p, kf.tuning_for(interval), [kf.vehicle.filter.initial_std]])
    x = np.repeat(initial.x[:, None], n, axis=1)
    P = np.repeat(np.array([initial.P[i, j] for i, j in PACKED])[:, None], n, axis=1)
    monitor = np.repeat(initial.m[:, None], n, axis=1)
    inputs = [np.ascontiguousarray(input_matrix(log), dtype=float) for log in logs]
    intervals = [np.ascontiguousarray(sample_intervals(log.t), dtype=float) for log in logs]
    n_faults = len(FAULT_CHANNELS)
    loads = [np.empty((length, 4)) for length in lengths]
    std = [np.empty((length, 4)) for length in lengths]
    residual = [np.empty((length, 3)) for length in lengths]
    statistic = [np.empty((length, n_faults)) for length in lengths]
    faults = [np.empty(length, np.uint32) for length in lengths]
    flags = [np.empty(length, np.uint32) for length in lengths]
    getattr(library, f"{PREFIX}_run_batch")(
        ctypes.c_int(n),
        ctypes.c_long(int(lengths.max())),
        _pointer(params),
        _pointers(inputs),
        _pointer(lengths),
        _pointers(intervals),
        _pointer(x),
        _pointer(P),
        _pointer(monitor),
        _pointers(loads),
        _pointers(std),
        _pointers(residual),
        _pointers(statistic),
        _pointers(faults),
        _pointers(flags),
    )
    estimates = []
    for b, log in enumerate(logs):
        fault = ((faults[b][:, None] >> np.arange(n_faults)) & 1).astype(float)
        estimates.append(
            Estimate(
                t=log.t.copy(),
                loads=loads[b],
                std=std[b],
                residual=residual[b],
                flags=flags[b].astype(np.int64) | log.input_flags(),
                sensor_faults=sensor_faults(log.t, fault, statistic[b]),
            )
        )
    return estimates
