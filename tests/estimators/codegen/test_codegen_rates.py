"""The generated example estimates the body-rate derivatives as the Python reader does.

wheelload's Python reader estimates ``wx_dot wy_dot wz_dot`` from ``wx wy wz``
(:func:`~wheelload.estimators.logs.signals.rate_derivatives`: a steady-state kinematic
Kalman filter per axis) when a log has the rates only; the generated library's
``wheelload_kf_rate_filter`` is the same filter, and the example program runs it where
the log has no derivative columns. On a log with rates and no derivatives the C equals
the Python filter (1e-9 relative, as tests/estimators/codegen/test_codegen.py), flags
included; the derivatives do feed the body-inertia terms (the filter without them
differs by more than 1 N).
"""

import dataclasses

import numpy as np
import pandas as pd
import pytest
from c_parity import assert_c_equals_python, c_estimates, kf_program

from wheelload.estimators import read_log, write_log
from wheelload.estimators.codegen.kf import CodegenOptions
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.result import WHEELS
from wheelload.models import example_vehicle_path
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


def test_codegen_bakes_the_rate_gain_of_its_sample_interval(tmp_path, capsys):
    """``codegen --sample-interval``: the rate filter's gain is the Python reader's at that
    interval (a log at 500 Hz needs the library generated for 0.002 s)."""
    from wheelload.estimators.logs.signals import RateDerivativeFilter
    from wheelload.studies.cli import main

    out = tmp_path / "c"
    assert main(["codegen", "--out", str(out), "--sample-interval", "0.002"]) == 0
    source = (out / "wheelload_kf.c").read_text()
    gain = [float(g) for g in RateDerivativeFilter().gain(0.002)]  # double: exact digits
    assert f"rate_gain[2] = {{{gain[0]!r}, {gain[1]!r}}};" in source
    assert "rate_interval = 0.002;" in source
    assert main(["codegen", "--out", str(tmp_path / "bad"), "--sample-interval", "0"]) == 2
    assert "sample interval must be > 0 s" in capsys.readouterr().err
