"""The generated library's batched step equals its single step; ``run_batched`` equals ``run``.

- Built with the strict flags (``-std=c99``: no FMA contraction), the batched
  step runs the same operations as the single step, so the self-test's
  ``batch-check`` (16 filters side by side against 16 single filters on a
  20 s scenario with lane changes, bumps into the stops and missing inputs)
  must find them bit-identical, flags included, in double and float.
- Built with ``FAST_CFLAGS`` the library compiles warning-free and gcc
  vectorises the loop over filters. Checked on the build :func:`run_batched` uses (the same
  C as ``wheelload codegen`` writes, under another prefix), whose warnings and vectoriser
  report gcc gave when it compiled it (kept beside the cached library): one -O3 compile
  serves both tests, and none when the build folder has it.
- :func:`run_batched` (the fast build: FMA contraction rounds once where the
  compiled ``run`` rounds twice) equals :meth:`TwoStageKF.run` to 1e-12
  relative, flag for flag, on logs of different lengths with missing and
  implausible samples.
"""

import platform
import re

import numpy as np
import pytest
from c_parity import assert_c_equals_python, compile_program, kf_library, run_program

from wheelload.estimators.codegen.batched import KERNEL_FLAGS, PREFIX, batch_library, run_batched
from wheelload.estimators.codegen.kf import FAST_CFLAGS, CodegenOptions
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import example_vehicle_path
from wheelload.models.runtime.build_folder import build_report


@pytest.mark.parametrize("precision", list(Precision))
def test_batched_step_is_bit_identical_to_the_single_step(tmp_path, precision):
    library = kf_library(example_vehicle_path(), tmp_path, CodegenOptions(precision=precision))
    binary = compile_program(library, library.selftest, "selftest")
    out = run_program(binary, "batch-check", "3000", "16").stdout
    values = dict(re.findall(r"(\w+) (\S+)", out))
    assert float(values["max_relative"]) == 0.0, out
    assert int(values["differing_flags"]) == 0, out
    assert int(values["flagged"]) > 1000, out  # the guards and skipped updates were exercised


def _code(text: str) -> str:
    """C text without its comments, whitespace collapsed (comments wrap with the prefix), and
    without the vehicle file's values (the default calibration and the build id with the
    file's hash): the batch library is built once per model structure, from whichever
    vehicle file of that structure came first, and its runs set every value."""
    text = re.sub(r"/\*.*?\*/|//[^\n]*", " ", text, flags=re.DOTALL)
    text = re.sub(r"(_default_params = \{).*?\n\};", r"\1 };", text, flags=re.DOTALL)
    text = re.sub(r"(_build_id\[\] =).*?;", r"\1 ;", text, flags=re.DOTALL)
    text = re.sub(r'(_VEHICLE_SHA256) "[0-9a-f]+"', r"\1", text)
    return " ".join(text.split())


@pytest.mark.skipif(platform.machine() != "x86_64", reason="vectoriser report checked on x86-64")
def test_fast_build_is_warning_free_and_vectorises_the_batch(vehicle, tmp_path):
    library = batch_library(TwoStageKF(vehicle).step_function, example_vehicle_path())
    # The build is KERNEL_FLAGS: FAST_CFLAGS with -Werror turned into this test's check.
    assert [flag for flag in KERNEL_FLAGS if flag in FAST_CFLAGS] == [
        flag for flag in FAST_CFLAGS if flag != "-Werror"
    ]
    # Its source is the library `wheelload codegen` writes (`make fast` compiles), header in
    # place, under the batch prefix: the same C, comments and the file's values aside.
    written = kf_library(example_vehicle_path(), tmp_path, CodegenOptions())
    text = written.source.read_text().replace(
        f'#include "{written.header.name}"', written.header.read_text(), 1
    )
    renamed = text.replace("wheelload_kf", PREFIX).replace("WHEELLOAD_KF", PREFIX.upper())
    assert _code(library.source) == _code(renamed)
    report = build_report(library.path)
    assert "warning:" not in report and "error:" not in report, report
    lines = library.source.splitlines()
    loop = next(k for k, line in enumerate(lines, start=1) if line.strip() == "IVDEP") + 1
    assert re.search(rf":{loop}:\d+: optimized: loop vectorized", report), report


def test_run_batched_equals_run_per_log(vehicle, plant_log):
    signals = plant_log("iso-dlc")
    logs = []
    for start, length in ((0, 900), (200, 400), (500, 700)):
        log = signals.slice(start, start + length)
        logs.append(log)
    d = logs[1].d.copy()
    d[50:60, 2] = np.nan  # missing travel: suspension update skipped
    d[120, 0] = 0.5  # implausible travel
    acc = logs[1].acc.copy()
    acc[300:, 1] = acc[299, 1]  # a stuck lateral accelerometer
    logs[1] = type(logs[1])(t=logs[1].t, vx=logs[1].vx, acc=acc, d=d, v=logs[1].v,
                            reference=logs[1].reference, source="edited")  # fmt: skip
    kf = TwoStageKF(vehicle)
    batched = run_batched(kf, example_vehicle_path(), logs)
    flags = 0
    for log, estimate in zip(logs, batched, strict=True):
        expected = kf.run(log)
        scale = np.abs(expected.loads).max()
        assert_c_equals_python(estimate.loads, expected.loads, rtol=1e-12, atol=1e-12 * scale)
        assert_c_equals_python(estimate.std, expected.std, rtol=1e-12, atol=0)
        assert_c_equals_python(estimate.residual, expected.residual, rtol=1e-7, atol=1e-12 * scale)
        np.testing.assert_array_equal(estimate.flags, expected.flags)
        # The same faults, their peak statistics to the loads' 1e-12 relative.
        assert [(f.channel, f.start, f.end) for f in estimate.sensor_faults] == [
            (f.channel, f.start, f.end) for f in expected.sensor_faults
        ]
        np.testing.assert_allclose(
            [f.statistic for f in estimate.sensor_faults],
            [f.statistic for f in expected.sensor_faults],
            rtol=1e-12,
        )
        flags |= np.bitwise_or.reduce(estimate.flags)
    assert flags & 0xFF, "skipped updates were exercised"


def test_monte_carlo_unit_equals_the_per_trial_unit(tmp_path):
    from wheelload.studies.experiments.runs.cache import ResultCache, cache_key
    from wheelload.studies.experiments.runs.units import (
        TRUTH,
        KfTrials,
        TrialSpec,
        TruthSpec,
        run_kf_trials,
        run_trial,
        simulate_truth,
    )

    text = example_vehicle_path().read_text()
    truth = TruthSpec(scenario="iso-dlc", vehicle_text=text)
    key = cache_key(TRUTH, truth)
    ResultCache(folder=tmp_path).store(key, simulate_truth(truth, tmp_path))
    specs = tuple(
        TrialSpec(
            truth=truth, vehicle_text=text, methods=("kf",), noise=noise, seed=seed, truth_key=key
        )  # fmt: skip
        for noise, seed in ((0.0, 1000), (1.0, 1001), (4.0, 1002))
    )
    batched = run_kf_trials(KfTrials(specs=specs), tmp_path)
    for spec, result in zip(specs, batched, strict=True):
        expected = run_trial(spec, tmp_path).metrics["kf"]
        # the loads agree to 1e-12 relative, so the metrics do to far better than 1e-9
        np.testing.assert_allclose(result.metrics["kf"].to_numpy(), expected.to_numpy(),
                                   rtol=1e-9)  # fmt: skip
    assert not np.allclose(batched[0].metrics["kf"], batched[2].metrics["kf"])  # noise differs
