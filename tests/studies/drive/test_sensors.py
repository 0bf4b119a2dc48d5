"""Sensor models: clean at s = 0, datasheet statistics at s = 1, linear in s."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wheelload.models.conventions import GRAVITY, WHEELS
from wheelload.studies.drive.scenario_log import LOG_COLUMNS
from wheelload.studies.drive.sensors import ImuModel, TravelSensorModel, measure, sensor_grade

RATE = 100.0


def _truth(count=20000):
    t = np.arange(1, count + 1) / RATE
    frame = pd.DataFrame({c: np.zeros(count) for c in LOG_COLUMNS})
    frame["t"] = t
    frame["az"] = GRAVITY
    for i, wheel in enumerate(WHEELS):
        frame[f"d_{wheel}"] = 0.02 * np.sin(2 * np.pi * 0.5 * t + i)
        frame[f"v_{wheel}"] = 0.02 * 2 * np.pi * 0.5 * np.cos(2 * np.pi * 0.5 * t + i)
    return frame


def test_zero_scale_gives_clean_signals():
    truth = _truth(500)
    log = measure(truth, 0.0, np.random.default_rng(1))
    pd.testing.assert_frame_equal(log, truth)


def test_imu_white_noise_matches_density_and_scales_linearly():
    truth = _truth()
    one = measure(truth, 1.0, np.random.default_rng(7))
    two = measure(truth, 2.0, np.random.default_rng(7))
    imu = ImuModel()
    for axis in ("ax", "ay", "az", "wx", "wy", "wz"):
        # Same seed: every stochastic IMU part is multiplied by s.
        np.testing.assert_allclose(
            two[axis] - truth[axis], 2.0 * (one[axis] - truth[axis]), rtol=1e-9, atol=1e-12
        )
    # White part: std of first differences / sqrt(2) (bias and slow walk cancel).
    expected = imu.accel_noise_density * np.sqrt(RATE / 2)
    measured = np.diff(one["ax"]).std() / np.sqrt(2)
    assert measured == pytest.approx(expected, rel=0.05)  # 20000 samples: ~1 % sampling error
    gyro = imu.gyro_noise_density * np.sqrt(RATE / 2)
    assert np.diff(one["wz"]).std() / np.sqrt(2) == pytest.approx(gyro, rel=0.05)


def test_travel_error_is_bounded_by_datasheet_figures():
    truth = _truth()
    log = measure(truth, 1.0, np.random.default_rng(3))
    model = TravelSensorModel()
    step = model.resolution
    bound = model.linearity * model.full_scale + 5 * model.repeatability + step
    for wheel in WHEELS:
        error = log[f"d_{wheel}"] - truth[f"d_{wheel}"]
        assert np.abs(error).max() <= bound
        assert np.abs(error).max() > 0.3 * model.linearity * model.full_scale
        # Quantised to the 12-bit step of the stroke.
        np.testing.assert_allclose(
            log[f"d_{wheel}"] / step, np.round(log[f"d_{wheel}"] / step), atol=1e-6
        )
        # v carries the backward difference of the displacement error, so v and d agree.
        np.testing.assert_allclose(
            (log[f"v_{wheel}"] - truth[f"v_{wheel}"]).to_numpy()[1:],
            np.diff(error.to_numpy()) * RATE,
            rtol=1e-9,
            atol=1e-12,
        )


def test_the_consumer_grade_has_its_stated_statistics():
    """White noise std, turn-on bias spread over seeds, travel step and noise, vx noise."""
    grade = sensor_grade("consumer-mems")
    imu, travel = grade.imu, grade.travel
    truth = _truth()
    biases = []
    for seed in range(40):
        log = measure(truth, 1.0, np.random.default_rng(seed), grade)
        biases.append([(log[a] - truth[a]).mean() for a in ("ax", "wz")])
        if seed == 0:
            # 20000 samples: ~1 % sampling error of a std, 5 % tolerance
            white = np.diff(log["ax"]).std() / np.sqrt(2)
            assert white == pytest.approx(imu.accel_noise_density * np.sqrt(RATE / 2), rel=0.05)
            gyro = np.diff(log["wz"]).std() / np.sqrt(2)
            assert gyro == pytest.approx(imu.gyro_noise_density * np.sqrt(RATE / 2), rel=0.05)
            assert (log["vx"] - truth["vx"]).std() == pytest.approx(grade.speed.noise, rel=0.05)
            for wheel in WHEELS:
                d = log[f"d_{wheel}"].to_numpy()
                # on the 0.1 mm logger step
                np.testing.assert_allclose(d / 0.1e-3, np.round(d / 0.1e-3), atol=1e-6)
                # white part: first differences of the error hold the noise and the step
                # (uniform, step^2/12), the smooth linearity error cancels
                error = d - truth[f"d_{wheel}"].to_numpy()
                expected = np.sqrt(travel.repeatability**2 + travel.resolution**2 / 12)
                assert np.diff(error).std() / np.sqrt(2) == pytest.approx(expected, rel=0.1)
    # turn-on bias: 40 seeds give the spread to ~11 % (1 sigma); the 200 s walk and the white
    # noise add < 1 % of it; 30 % tolerance
    spread = np.std(biases, axis=0)
    assert spread[0] == pytest.approx(imu.accel_bias, rel=0.3)
    assert spread[1] == pytest.approx(imu.gyro_bias, rel=0.3)
    # the grade is 2.5x the MTi-1 grade's noise densities and turn-on biases
    mti = ImuModel()
    assert imu.accel_noise_density / mti.accel_noise_density == pytest.approx(2.5)
    assert imu.gyro_bias / mti.gyro_bias == pytest.approx(2.5)


def test_the_clean_grade_is_noise_free_and_a_bad_name_is_named():
    truth = _truth(500)
    log = measure(truth, 1.0, np.random.default_rng(1), sensor_grade("clean"))
    pd.testing.assert_frame_equal(log, truth)
    with pytest.raises(ValueError, match="unknown sensor grade 'mems'; choose from clean"):
        sensor_grade("mems")


def test_paper_scalings_scale_only_what_the_paper_perturbs():
    """Same seed, s = 4 against s = 1: under both paper scalings the gyroscopes (and under
    PAPER_STOCHASTIC the accelerometers' turn-on bias and the travel linearity curve) keep
    their nominal errors exactly; the accelerometers' random part grows 4 times."""
    from wheelload.studies.drive.sensors import NoiseScaling

    truth = _truth(3000)

    def errors(scaling, s):
        log = measure(truth, s, np.random.default_rng(5), scaling=scaling)
        return {c: log[c].to_numpy() - truth[c].to_numpy() for c in ("ax", "wx", "d_fl")}

    for scaling in (NoiseScaling.PAPER_SENSORS, NoiseScaling.PAPER_STOCHASTIC):
        one, four = errors(scaling, 1.0), errors(scaling, 4.0)
        np.testing.assert_array_equal(four["wx"], one["wx"])  # gyroscope: nominal
        assert np.std(np.diff(four["ax"])) == pytest.approx(4 * np.std(np.diff(one["ax"])))
    # ALL at s = 1 is the nominal log of either paper scaling (common random numbers).
    nominal = errors(NoiseScaling.ALL, 1.0)
    for scaling in (NoiseScaling.PAPER_SENSORS, NoiseScaling.PAPER_STOCHASTIC):
        np.testing.assert_array_equal(errors(scaling, 1.0)["d_fl"], nominal["d_fl"])
    # The turn-on bias is the accelerometer error's mean: x4 under PAPER_SENSORS, x1 under
    # PAPER_STOCHASTIC (the white noise and walk of 3000 samples move the mean far less).
    bias_one = np.mean(nominal["ax"])
    sensors = np.mean(errors(NoiseScaling.PAPER_SENSORS, 4.0)["ax"])
    stochastic = np.mean(errors(NoiseScaling.PAPER_STOCHASTIC, 4.0)["ax"])
    assert abs(bias_one) > 0.005  # 1 sigma is 0.049 m/s^2 (5 mg); this seed draws one
    assert sensors == pytest.approx(4 * bias_one, rel=0.05)
    assert stochastic == pytest.approx(bias_one, rel=0.05)
    # The travel error of PAPER_STOCHASTIC at s = 0 is the linearity curve and the step only.
    zero = errors(NoiseScaling.PAPER_STOCHASTIC, 0.0)["d_fl"]
    assert np.max(np.abs(zero)) <= TravelSensorModel().linearity * 0.150 + 0.150 / 2**12
