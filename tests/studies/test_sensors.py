"""Sensor models: clean at s = 0, datasheet statistics at s = 1, linear in s."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wheelload.models.conventions import GRAVITY, WHEELS
from wheelload.studies.drive.scenario_log import LOG_COLUMNS
from wheelload.studies.drive.sensors import ImuModel, TravelSensorModel, measure

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
