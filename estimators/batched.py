"""Many logs through the generated library's batched step, side by side.

:func:`run_batched` filters several logs (or Monte Carlo trials) at once:
the two-stage KF's C library is generated from the filter's own step
Function (:mod:`wheelload.estimators.codegen`, runtime parameters, double),
built once with the Makefile's ``FAST_CFLAGS`` (cached in the private build
folder by the hash of its source and flags) and stepped ``n`` filters at a
time through ``wheelload_batch_step_batch`` (struct of arrays, vectorised
across the filters). Logs of different lengths are padded with rejected
samples (the state is held) whose outputs are dropped; logs are grouped by
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

from wheelload.estimators.c_emitter import Precision
from wheelload.estimators.codegen import FAST_CFLAGS, PACKED, CodegenOptions, generate
from wheelload.estimators.compiled import _shared_library
from wheelload.estimators.guard import FAULT_CHANNELS
from wheelload.estimators.result import Estimate
from wheelload.estimators.signals import Signals
from wheelload.estimators.two_stage import (
    TwoStageKF,
    input_matrix,
    nominal_interval,
    sample_intervals,
    sensor_faults,
)
from wheelload.models import INPUTS
from wheelload.models.build_folder import build_folder

PREFIX = "wheelload_batch"
#: Time steps handed to C per call (bounds the side-by-side input copy).
CHUNK = 4096
#: The fast build of the library as a shared object (warnings are not errors here).
SHARED_FLAGS = (
    "gcc",
    *(flag for flag in FAST_CFLAGS if not flag.startswith("-W")),
    "-fPIC",
    "-shared",
)

DRIVER = """
#include <string.h>

/* steps x (n filters side by side): input [steps][N_INPUTS][n], dt [steps][n];
   outputs [steps][rows][n]; the state x, P, monitor is carried in place. */
void ${prefix}_run_batch(int n, long steps, const ${prefix}_params *params,
                         const ${prefix}_real *input, const ${prefix}_real *dt,
                         ${prefix}_real *x, ${prefix}_real *P, ${prefix}_real *monitor,
                         ${prefix}_real *loads, ${prefix}_real *std, ${prefix}_real *residual,
                         ${prefix}_real *statistic, uint32_t *faults, uint32_t *flags)
{
    ${prefix}_batch batch;
    long k;
    batch.n = n;
    batch.x = x;
    batch.P = P;
    batch.monitor = monitor;
    for (k = 0; k < steps; ++k) {
        ${prefix}_batch_output output;
        output.std = std + k * 4 * n;
        output.residual = residual + k * 3 * n;
        output.fault_statistic = statistic + k * ${PREFIX}_N_FAULT_CHANNELS * n;
        output.faults = faults + k * n;
        output.flags = flags + k * n;
        ${prefix}_step_batch(&batch, params, input + k * ${PREFIX}_N_INPUTS * n, dt + k * n,
                             &output);
        memcpy(loads + k * 4 * n, x, sizeof(${prefix}_real) * 4 * (size_t)n);
    }
}
"""


@functools.lru_cache(maxsize=4)
def _library(step: ca.Function, vehicle_path: Path) -> ctypes.CDLL:
    """The generated library for ``step`` with the batch driver, built and loaded."""
    options = CodegenOptions(precision=Precision.DOUBLE, prefix=PREFIX)
    with tempfile.TemporaryDirectory(dir=build_folder()) as folder:
        library = generate(vehicle_path, folder, options, step, allow_unusual=True)
        header = library.header.read_text()
        source = library.source.read_text().replace(f'#include "{PREFIX}.h"', header, 1)
    driver = DRIVER.replace("${prefix}", PREFIX).replace("${PREFIX}", PREFIX.upper())
    shared = _shared_library(source + driver, PREFIX, SHARED_FLAGS)
    function = getattr(shared, f"{PREFIX}_run_batch")
    function.restype = None
    return shared


def _pointer(array: np.ndarray) -> ctypes.c_void_p:
    return ctypes.c_void_p(array.ctypes.data)


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
    """Logs with the same nominal interval, stepped side by side."""
    n, lengths = len(logs), [len(log) for log in logs]
    steps = max(lengths)
    initial = kf.initial_state()
    params = np.concatenate([kf.p, kf.tuning_for(interval), [kf.vehicle.filter.initial_std]])
    x = np.repeat(initial.x[:, None], n, axis=1).copy()
    P = np.repeat(np.array([initial.P[i, j] for i, j in PACKED])[:, None], n, axis=1).copy()
    monitor = np.repeat(initial.m[:, None], n, axis=1).copy()
    inputs = [input_matrix(log) for log in logs]  # (n_inputs, length) each
    intervals = [sample_intervals(log.t) for log in logs]
    n_faults = len(FAULT_CHANNELS)
    loads, std = np.empty((steps, 4, n)), np.empty((steps, 4, n))
    residual, statistic = np.empty((steps, 3, n)), np.empty((steps, n_faults, n))
    faults, flags = np.empty((steps, n), np.uint32), np.empty((steps, n), np.uint32)
    run = getattr(library, f"{PREFIX}_run_batch")
    for start in range(0, steps, CHUNK):
        stop = min(start + CHUNK, steps)
        u = np.full((stop - start, len(INPUTS), n), np.nan)
        dt = np.full((stop - start, n), np.nan)  # past a log's end: rejected, state held
        for b, (matrix, interval_b) in enumerate(zip(inputs, intervals)):
            end = min(stop, lengths[b])
            if end > start:
                u[: end - start, :, b] = matrix[:, start:end].T
                dt[: end - start, b] = interval_b[start:end]
        run(
            ctypes.c_int(n),
            ctypes.c_long(stop - start),
            _pointer(params),
            _pointer(u),
            _pointer(dt),
            _pointer(x),
            _pointer(P),
            _pointer(monitor),
            _pointer(loads[start:stop]),
            _pointer(std[start:stop]),
            _pointer(residual[start:stop]),
            _pointer(statistic[start:stop]),
            _pointer(faults[start:stop]),
            _pointer(flags[start:stop]),
        )
    estimates = []
    for b, log in enumerate(logs):
        length = lengths[b]
        fault = ((faults[:length, b, None] >> np.arange(n_faults)) & 1).astype(float)
        estimates.append(
            Estimate(
                t=log.t.copy(),
                loads=np.ascontiguousarray(loads[:length, :, b]),
                std=np.ascontiguousarray(std[:length, :, b]),
                residual=np.ascontiguousarray(residual[:length, :, b]),
                flags=flags[:length, b].astype(np.int64) | log.input_flags(),
                sensor_faults=sensor_faults(log.t, fault, statistic[:length, :, b]),
            )
        )
    return estimates
