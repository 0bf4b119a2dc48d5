"""The generated example at any log rate; the body-rate derivatives as the Python reader's.

wheelload's Python reader estimates ``wx_dot wy_dot wz_dot`` from ``wx wy wz``
(:func:`~wheelload.estimators.logs.signals.rate_derivatives`: a steady-state kinematic
Kalman filter per axis) when a log has the rates only; the generated library's
``wheelload_kf_rate_filter`` is the same filter, and the example program runs it where
the log has no derivative columns. On a log with rates and no derivatives the C equals
the Python filter (1e-9 relative, as tests/estimators/codegen/test_codegen.py), flags
included; the derivatives do feed the body-inertia terms (the filter without them
differs by more than 1 N).

At another rate than the library's interval, the C equals Python or refuses with a status
bit, never silently off: a library built for 100 Hz refuses a 500 Hz log (INTERVAL_SHORT,
counted and reported, as the Python filter given that nominal interval does), equals the
Python filter once given the log's interval at run time, and a library built for 500 Hz
equals the Python tyre step too.
"""

import dataclasses

import numpy as np
import pandas as pd
import pytest
from c_parity import (
    assert_c_equals_python,
    c_estimates,
    kf_program,
    mhe_program,
    run_program,
)

from wheelload.estimators import read_log, write_log
from wheelload.estimators.codegen.kf import CodegenOptions
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.registry import build
from wheelload.estimators.result import WHEELS, StepFlag
from wheelload.models import ModelParameters, example_vehicle_path, load_vehicle
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log
from wheelload.studies.pipeline.example_log import example_log_path

LOADS = [f"fz_{w}" for w in WHEELS]


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """The example program of the bundled vehicle (double, runtime parameters), built once."""
    folder = tmp_path_factory.mktemp("c")
    return kf_program(example_vehicle_path(), folder, CodegenOptions())


def test_example_on_the_bundled_log_equals_the_python_filter(vehicle, example, tmp_path):
    """The bundled log has the rates and no derivative columns: the example program, with
    no extra column, equals the Python filter (``wheelload estimate``'s) to 1e-9 relative,
    flags included (before the rate filter: up to 216 N apart)."""
    c = c_estimates(example, example_log_path(), tmp_path / "estimates.csv")
    python = TwoStageKF(vehicle).run(read_log(example_log_path()))
    assert python.flags.size == len(c)
    scale = np.abs(python.loads).max()
    assert_c_equals_python(c[LOADS], python.loads, rtol=1e-9, atol=1e-9 * scale)
    np.testing.assert_array_equal(c["status"], python.flags)


def test_example_derives_the_rate_terms_as_python_does(vehicle, example, tmp_path):
    signals = synthetic_log(
        vehicle, slalom(duration=6.0), noise=SensorNoise(acceleration=0.05, travel=0.0003)
    )
    t = signals.t
    w = 2 * np.pi * 0.4
    rates = np.column_stack(
        [-0.3 * np.cos(w * t), 0.2 * np.sin(w * t), signals.acc[:, 1] / signals.vx]
    )
    signals = dataclasses.replace(signals, rates=rates, rate_dots=None)
    log = tmp_path / "rates_only.csv"
    write_log(signals, log)
    assert not {"wx_dot", "wy_dot", "wz_dot"} & set(pd.read_csv(log).columns)

    c = c_estimates(example, log, tmp_path / "estimates.csv")

    read = read_log(log)
    derived = TwoStageKF(vehicle).run(read)
    missing = TwoStageKF(vehicle).run(
        dataclasses.replace(read, rate_dots=np.full((len(read), 3), np.nan))
    )
    scale = np.abs(derived.loads).max()
    assert_c_equals_python(c[LOADS], derived.loads, rtol=1e-9, atol=1e-9 * scale)
    np.testing.assert_array_equal(c["status"], derived.flags)
    # The derived derivatives feed the body-inertia terms: other loads, other flags.
    assert np.abs(derived.loads - missing.loads).max() > 1.0  # N
    assert (derived.flags != missing.flags).any()


def test_codegen_takes_one_interval_option_and_says_the_old_ones_are_deprecated(tmp_path, capsys):
    """``codegen --interval`` for the KF and the MHE; ``--sample-interval`` and ``--dt`` still
    work and say they are deprecated; two different values are refused. The rate filter's
    gain is no longer baked: the library computes it at run time (its constants are)."""
    from wheelload.estimators.logs.signals import RateDerivativeFilter
    from wheelload.studies.cli import main

    assert main(["codegen", "--out", str(tmp_path / "a"), "--interval", "0.002"]) == 0
    assert "deprecated" not in capsys.readouterr().err
    header = (tmp_path / "a" / "wheelload_kf.c").read_text()
    assert "0.002, /* sample_interval */" in header
    assert f"RATE_JERK_DENSITY {RateDerivativeFilter().jerk_density!r}" in header
    assert main(["codegen", "--out", str(tmp_path / "b"), "--sample-interval", "0.002"]) == 0
    assert "--sample-interval is deprecated: use --interval" in capsys.readouterr().err
    assert "0.002, /* sample_interval */" in (tmp_path / "b" / "wheelload_kf.c").read_text()
    assert main(["codegen", "--out", str(tmp_path / "c"), "--interval", "0.002",
                 "--dt", "0.01"]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert "--dt is deprecated" in err and "give different intervals" in err
    assert main(["codegen", "--out", str(tmp_path / "d"), "--interval", "0"]) == 2
    assert "sample interval must be > 0 s" in capsys.readouterr().err


@pytest.fixture(scope="module")
def log_500_hz(tmp_path_factory):
    """The plant's lane change logged at 500 Hz (5x the library's default interval)."""
    frame = run_scenario("iso-dlc", example_vehicle_path(), output_rate=500.0).log
    path = tmp_path_factory.mktemp("log500") / "dlc500.csv"
    frame.to_csv(path, index=False, float_format="%.17g")
    return path


@pytest.fixture(scope="module")
def example_100_hz(tmp_path_factory):
    """The example with the tyre step, built for the default 0.01 s (100 Hz)."""
    folder = tmp_path_factory.mktemp("c100")
    return kf_program(example_vehicle_path(), folder, CodegenOptions(tyre_forces=True))


def _fx(frame):
    return frame[[f"fx_{w}" for w in WHEELS]].to_numpy()


def test_a_100_hz_library_on_a_500_hz_log_refuses_with_the_status_bit(
    vehicle, example_100_hz, log_500_hz, tmp_path
):
    """Before: loads up to 69.4 N off Python, F_x 18.5 N, status 0, exit 0. Now every step
    is refused with INTERVAL_SHORT (dt 0.002 s < 0.01 s / 1.5), the state held at the static
    loads, and the example says how many and the fix; the Python filter given the same
    nominal interval does the same (C = Python, 1e-9 relative); the tyre step refuses too
    (its observers are discretised at 0.01 s) and says so."""
    result = run_program(example_100_hz, log_500_hz, tmp_path / "c.csv", check=False)
    assert result.returncode == 0, result.stderr
    c = pd.read_csv(tmp_path / "c.csv")
    n = len(c)
    assert ((c["status"].to_numpy() & int(StepFlag.INTERVAL_SHORT)) != 0).all()
    assert f"{n} steps refused (status bit INTERVAL_SHORT)" in result.stderr
    assert "sample_interval=SECONDS" in result.stderr
    assert f"{n} tyre steps refused" in result.stderr
    static = ModelParameters.from_vehicle(vehicle)
    statics = [getattr(static, f"static_{w}") for w in WHEELS]
    np.testing.assert_array_equal(c[LOADS].to_numpy(), np.tile(statics, (n, 1)))
    assert (_fx(c) == 0.0).all()  # no tyre step taken: the start's zero forces
    python = TwoStageKF(vehicle, sample_interval=0.01).run(read_log(log_500_hz))
    scale = np.abs(python.loads).max()
    assert_c_equals_python(c[LOADS], python.loads, rtol=1e-9, atol=1e-9 * scale)
    np.testing.assert_array_equal(c["status"], python.flags)


def test_a_100_hz_library_given_the_log_interval_equals_python_at_500_hz(
    vehicle, example_100_hz, log_500_hz, tmp_path
):
    """The same library with ``sample_interval=0.002`` (run time, no rebuild): the loads
    within 1e-9 N of ``wheelload estimate``'s filter on the 500 Hz log (measured 1.8e-12 N),
    flags equal (the rate-derivative filter's gain computed for 0.002 s at run time)."""
    c = c_estimates(example_100_hz, log_500_hz, tmp_path / "c.csv", "sample_interval=0.002")
    python = TwoStageKF(vehicle).run(read_log(log_500_hz))
    assert_c_equals_python(c[LOADS], python.loads, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(c["status"], python.flags)
    assert not (
        c["status"].to_numpy() & int(StepFlag.INTERVAL_SHORT | StepFlag.INTERVAL_LONG)
    ).any()


def test_a_library_built_for_500_hz_equals_the_python_tyre_forces(log_500_hz, tmp_path):
    """Built with ``interval=0.002``: F_z, F_x and F_y within 1e-9 N of the Python
    ``tyre-forces`` method on the 500 Hz log, no step refused."""
    options = CodegenOptions(tyre_forces=True, sample_interval=0.002)
    binary = kf_program(example_vehicle_path(), tmp_path / "c500", options)
    result = run_program(binary, log_500_hz, tmp_path / "c.csv")
    assert "refused" not in result.stderr
    c = pd.read_csv(tmp_path / "c.csv")
    python = build("tyre-forces", load_vehicle(example_vehicle_path())).run(read_log(log_500_hz))
    assert_c_equals_python(c[LOADS], python.loads, rtol=0, atol=1e-9, what="fz")
    assert_c_equals_python(_fx(c), python.fx, rtol=0, atol=1e-9, what="fx")
    fy = c[[f"fy_{w}" for w in WHEELS]].to_numpy()
    assert_c_equals_python(fy, python.fy, rtol=0, atol=1e-9, what="fy")


def test_the_embedded_mhe_refuses_a_faster_log_with_the_status_bit(vehicle, log_500_hz, tmp_path):
    """The embedded MHE generated for 0.01 s on the 500 Hz log: nothing solved, every sample
    flagged 255 | INTERVAL_SHORT (before: solved with the cost scale, the arrival weight and
    the linked filter's noise of 0.01 s, silently); generated for 0.002 s it solves them."""
    from wheelload.estimators import MheSettings
    from wheelload.estimators.codegen.mhe_build import write_inputs

    rows = write_inputs(read_log(log_500_hz).slice(0, 200), tmp_path / "rows.txt")
    settings = MheSettings(horizon=5)
    for dt, refused in ((0.01, True), (0.002, False)):
        folder = tmp_path / f"mhe_{dt}"
        binary = mhe_program(vehicle, settings, folder, dt, vehicle_path=example_vehicle_path())
        run_program(binary, rows, folder / "out.csv")
        flags = pd.read_csv(folder / "out.csv")["flags"].to_numpy()
        short = (flags & int(StepFlag.INTERVAL_SHORT)) != 0
        assert short.all() if refused else not short.any(), dt
        if refused:
            assert ((flags & 255) == 255).all()
