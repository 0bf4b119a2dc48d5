"""Timing workloads of the two-stage KF's step: Python, filterpy, the generated C self-test.

Each returns times (or per-step callables to time); the ``wheelload bench``
commands print them beside each other. Printed, never asserted.
"""

from __future__ import annotations

import re
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np

from wheelload.estimators import Sample
from wheelload.estimators.codegen.batched import run_batched
from wheelload.estimators.codegen.kf import CodegenOptions, build_program, generate
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.kf.tuning import TUNING
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.protocol import sample_intervals
from wheelload.studies.bench.numpy_kf import pseudo_measurements


def spread(values: list[float]) -> str:
    """``min / median / max`` of ``values``."""
    return f"{min(values):.3g} / {statistics.median(values):.3g} / {max(values):.3g}"


def step_samples(signals, n: int) -> list[Sample]:
    """The first ``n`` samples of a log as the step's inputs."""
    return [
        Sample(d=signals.d[k], v=signals.v[k], acc=signals.acc[k], vx=signals.vx[k])
        for k in range(n)
    ]


def per_call_us(function, n: int) -> float:
    """Mean µs of ``function(k)`` over ``k = 0 .. n-1``."""
    start = time.perf_counter()
    for k in range(n):
        function(k)
    return (time.perf_counter() - start) / n * 1e6


def median_ns(step, n: int) -> float:
    """Median ns of ``step(k)`` over ``k = 0 .. n-1``."""
    times = []
    for k in range(n):
        start = time.perf_counter_ns()
        step(k)
        times.append(time.perf_counter_ns() - start)
    return float(statistics.median(times))


def python_steps(kf: TwoStageKF, signals, n: int):
    """Per-step callables: fast step, reference step, filterpy (None if not installed)."""
    dt = sample_intervals(signals.t)
    samples = step_samples(signals, n)
    states = {"fast": kf.initial_state(), "reference": kf.initial_state()}

    def fast(k):
        states["fast"], _ = kf.step(states["fast"], samples[k], dt[k])

    def reference(k):
        states["reference"], _ = kf.reference_step(states["reference"], samples[k], dt[k])

    return fast, reference, filterpy_step(kf, signals)


def live_steps(kf: TwoStageKF, signals, n: int):
    """Per-step callable of the lean path: :meth:`TwoStageKF.live`'s ``update``."""
    dt = sample_intervals(signals.t)
    samples = step_samples(signals, n)
    live = kf.live()

    def lean(k):
        live.update(samples[k], dt[k])

    return lean


def python_step_ns(kf: TwoStageKF, signals, n: int) -> float:
    """Median ns of one :meth:`TwoStageKF.step` (CasADi virtual machine)."""
    dt = sample_intervals(signals.t)
    samples = step_samples(signals, n)
    state = [kf.initial_state()]

    def step(k):
        state[0], _ = kf.step(state[0], samples[k], dt[k])

    return median_ns(step, n)


def filterpy_step(kf: TwoStageKF, signals):
    """filterpy's predict + suspension update + equilibrium update as a per-sample
    callable ``step(k)`` (None if filterpy is not installed).

    The pseudo-measurements z and b are computed here, beforehand, and not timed.
    """
    try:
        from filterpy.kalman import KalmanFilter
    except ImportError:
        return None
    z, A, b = pseudo_measurements(signals, kf.p)
    dt = sample_intervals(signals.t)
    q, rs, rc = (
        TUNING.value(kf.tuning, name)
        for name in (
            "process_noise_density",
            "suspension_noise_density",
            "constraint_noise_density",
        )
    )
    filt = KalmanFilter(dim_x=4, dim_z=4)
    initial = kf.initial_state()
    filt.x, filt.P, filt.F = initial.x[:, None].copy(), initial.P.copy(), np.eye(4)
    H_s = np.eye(4)

    def step(k):
        filt.Q = q * dt[k] * np.eye(4)
        filt.predict()
        filt.update(z[k][:, None], R=rs / dt[k] * np.eye(4), H=H_s)
        filt.update(b[k][:, None], R=np.diag(rc / dt[k]), H=A)

    return step


def filterpy_step_ns(kf: TwoStageKF, signals, n: int) -> float | None:
    """Median ns of :func:`filterpy_step` (None if filterpy is not installed)."""
    step = filterpy_step(kf, signals)
    return None if step is None else median_ns(step, n)


def cpu_mhz() -> float | None:
    """Clock frequency from /proc/cpuinfo (Linux), or None."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return None
    match = re.search(r"cpu MHz\s*:\s*([\d.]+)", text)
    return float(match.group(1)) if match else None


def c_step_ns(
    vehicle_path: Path,
    precision: Precision,
    folder: Path,
    samples: int,
    repeats: int,
    allow_unusual: bool = False,
):
    """Median and minimum ns per step of the library's self-test benchmark, and the library."""
    library = generate(
        vehicle_path,
        folder / precision.value,
        CodegenOptions(precision=precision),
        allow_unusual=allow_unusual,
    )
    binary = build_program(library, library.selftest, folder / precision.value / "selftest")
    out = subprocess.run(
        [str(binary), "bench", str(samples), str(repeats)], capture_output=True, text=True,
        check=True,
    ).stdout  # fmt: skip
    median, least = (
        float(re.search(rf"{key} (\S+)", out).group(1)) for key in ("median_ns", "min_ns")
    )
    return median, least, library


def selftest_ns(binary: Path, *arguments) -> float:
    """Fastest of the self-test's internal repeats [ns per (filter-)step]."""
    out = subprocess.run(
        [str(binary), *map(str, arguments)], capture_output=True, text=True, check=True
    ).stdout
    return float(re.search(r"min_ns (\S+)", out).group(1))


def selftest_median_ns(binary: Path, *arguments) -> float:
    """Median of the self-test's internal repeats [ns per (filter-)step]."""
    out = subprocess.run(
        [str(binary), *map(str, arguments)], capture_output=True, text=True, check=True
    ).stdout
    return float(re.search(r"median_ns (\S+)", out).group(1))


def fast_selftest(
    vehicle_path: Path, folder: Path, options: CodegenOptions, flags, allow_unusual: bool = False
):
    """The generated library and its self-test built with ``flags``: ``(library, binary)``."""
    library = generate(vehicle_path, folder, options, allow_unusual=allow_unusual)
    binary = build_program(library, library.selftest, folder / "selftest_fast", flags=flags)
    return library, binary


def single_and_batched_ns(
    binary: Path, samples: int, passes: int, batch: int, repeats: int
) -> tuple[list[float], list[float]]:
    """ns per step of the self-test's single step and per filter-step of its batch of
    ``batch`` filters (each the fastest of ``passes`` passes), ``repeats`` times in turn."""
    single, batched = [], []
    for _ in range(repeats):
        single.append(selftest_ns(binary, "bench", samples, passes))
        batched.append(selftest_ns(binary, "batch-bench", max(samples // batch, 1), passes, batch))
    return single, batched


def batched_against_run(kf: TwoStageKF, vehicle_path: Path, logs: list, repeats: int):
    """µs per sample of :func:`~wheelload.estimators.codegen.batched.run_batched` over the
    logs and of :meth:`TwoStageKF.run` on each, ``repeats`` times in turn: two lists."""
    samples = sum(len(log) for log in logs)
    run_batched(kf, vehicle_path, logs[:2])  # build (or load) the library
    kf.run(logs[0].slice(0, 10))
    batched, single = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        run_batched(kf, vehicle_path, logs)
        batched.append((time.perf_counter() - start) / samples * 1e6)
        start = time.perf_counter()
        for log in logs:
            kf.run(log)
        single.append((time.perf_counter() - start) / samples * 1e6)
    return batched, single
