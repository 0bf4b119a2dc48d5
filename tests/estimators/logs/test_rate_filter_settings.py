"""The body-rate derivative filter takes its noise from the vehicle file.

``[sensors] gyro_noise_density`` (the gyroscope's data-sheet density N) and ``[filter]
rate_jerk_density`` (q) set :class:`~wheelload.estimators.logs.signals.RateDerivativeFilter`
for every path that derives ``wx_dot .. wz_dot`` from ``wx .. wz``: the KF's ``run`` and
``step``, the streamed estimate and the generated C. A file without them gets the MTi-1
class figures the filter had as constants, so the bundled files' results are unchanged.
"""

import math

import numpy as np
import pytest
import scipy.linalg

from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import DEFAULT_RATE_FILTER, RateDerivativeFilter
from wheelload.estimators.samples import step_through
from wheelload.models import INPUTS, example_vehicle_path, load_vehicle
from wheelload.models.vehicle.file import add_values
from wheelload.models.vehicle.sensor_section import MTI_1_GYRO_NOISE_DENSITY

CONSUMER_GYRO = 3.0543e-4  # rad/s/sqrt(Hz): 0.0175 deg/s/sqrt(Hz), studies/drive/sensors.py MEMS
RATE_DOTS = [INPUTS.index(name) for name in ("wx_dot", "wy_dot", "wz_dot")]
RATES = [INPUTS.index(name) for name in ("wx", "wy", "wz")]


@pytest.fixture(scope="module")
def noisy_file(tmp_path_factory):
    """The bundled file with a consumer gyroscope and a jerk density of 4, as a user writes it."""
    text = example_vehicle_path().read_text(encoding="utf-8")
    text = add_values(text, {("sensors", "gyro_noise_density"): (CONSUMER_GYRO, "MEMS"),
                             ("filter", "rate_jerk_density"): (4.0, "")})  # fmt: skip
    path = tmp_path_factory.mktemp("vehicle") / "car.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_a_file_without_the_keys_keeps_the_mti_1_figures(vehicle):
    assert RateDerivativeFilter.of(vehicle) == DEFAULT_RATE_FILTER
    assert DEFAULT_RATE_FILTER.gyro_noise_density == MTI_1_GYRO_NOISE_DENSITY
    assert MTI_1_GYRO_NOISE_DENSITY == pytest.approx(0.007 * math.pi / 180.0, rel=1e-15)


def test_the_file_states_the_filter(noisy_file):
    settings = RateDerivativeFilter.of(load_vehicle(noisy_file))
    assert settings.gyro_noise_density == pytest.approx(CONSUMER_GYRO, rel=1e-12)
    assert settings.jerk_density == 4.0


def _alpha_beta(T, q, N, rates):
    """The kinematic filter written out: gain from scipy's discrete Riccati solution (not the
    project's iteration), the alpha-beta recursion in numpy, started at [w0, 0]."""
    F = np.array([[1.0, T], [0.0, 1.0]])
    Q = q * np.array([[T**3 / 3.0, T**2 / 2.0], [T**2 / 2.0, T]])
    H = np.array([[1.0, 0.0]])
    R = np.array([[N**2 / (2.0 * T)]])
    P = scipy.linalg.solve_discrete_are(F.T, H.T, Q, R)  # the predicted covariance
    K = (P @ H.T / (H @ P @ H.T + R)).ravel()
    out = np.empty_like(rates)
    for axis in range(rates.shape[1]):
        w, w_dot = rates[0, axis], 0.0
        for k, z in enumerate(rates[:, axis]):
            predicted = w + T * w_dot
            residual = z - predicted
            w, w_dot = predicted + K[0] * residual, w_dot + K[1] * residual
            out[k, axis] = w_dot
    return out


def test_the_kf_derives_the_rate_derivatives_with_the_files_noise(plant_log, noisy_file):
    """The KF's inputs carry the file's filter: equal to an independent alpha-beta filter with
    the file's q and N (1e-9 rad/s^2), and apart from the default filter's (MEMS noise in the
    file smooths: the derivative's sample-to-sample scatter falls)."""
    signals = plant_log("iso-dlc").slice(0, 600)
    kf = TwoStageKF(load_vehicle(noisy_file))
    derived = input_matrix(signals, kf.rate_filter)[RATE_DOTS].T
    T = float(np.median(np.diff(signals.t)))
    expected = _alpha_beta(T, 4.0, CONSUMER_GYRO, signals.rates)
    np.testing.assert_allclose(derived, expected, rtol=0, atol=1e-9)
    default = input_matrix(signals)[RATE_DOTS].T
    assert np.abs(derived - default).max() > 0.01  # rad/s^2 (0.035 on this slice)
    assert np.std(np.diff(derived, axis=0)) < np.std(np.diff(default, axis=0))


def test_step_and_run_take_the_same_filter(plant_log, noisy_file):
    """``step`` (through :func:`step_through`, the samples' derivatives) and ``run`` (the
    compiled loop) give the same loads for a file with its own gyroscope (1e-9 N)."""
    signals = plant_log("iso-dlc").slice(0, 300)
    kf = TwoStageKF(load_vehicle(noisy_file), check_file=False)
    run = kf.run(signals)
    stepped = step_through(kf, signals)
    np.testing.assert_allclose(stepped.loads, run.loads, rtol=0, atol=1e-9)
    other = TwoStageKF(load_vehicle(example_vehicle_path()), check_file=False).run(signals)
    assert np.abs(other.loads - run.loads).max() > 0.01  # N: the derivatives feed the loads


def test_the_generated_c_bakes_the_files_noise(noisy_file, tmp_path):
    """``codegen`` of that file writes its q and N as the C rate filter's constants (the C's
    run-time gain follows them; tests/estimators/codegen/test_codegen_rates.py runs the C
    filter against Python's)."""
    from wheelload.studies.cli import main

    assert main(["codegen", "--vehicle", str(noisy_file), "--out", str(tmp_path / "c")]) == 0
    source = (tmp_path / "c" / "wheelload_kf.c").read_text()
    assert f"RATE_GYRO_NOISE_DENSITY {CONSUMER_GYRO!r}" in source
    assert "RATE_JERK_DENSITY 4.0" in source
