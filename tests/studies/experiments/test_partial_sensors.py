"""Partial sensor sets on a plant log: finite output, bounded sigma, the mode named."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import StepFlag, signals_from_frame
from wheelload.estimators.kf.tuning import with_filter_sigma
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models.conventions import WHEELS
from wheelload.studies.cli import main
from wheelload.studies.metrics import wheel_metrics
from wheelload.studies.pipeline.summary import row_use, summary

TRAVEL = [f"d_{w}" for w in WHEELS] + [f"v_{w}" for w in WHEELS]


@pytest.fixture(scope="module")
def plant_log(tmp_path_factory):
    path = tmp_path_factory.mktemp("plant") / "iso-dlc.parquet"
    assert main(["simulate", "iso-dlc", "--out", str(path)]) == 0
    return pd.read_parquet(path)


def _dead(frame, wheels):
    frame = frame.copy()
    frame[[f"{kind}_{w}" for w in wheels for kind in ("d", "v")]] = np.nan
    return frame


# name, frame edit, words in the mode, sigma bound [N], pooled RMSE bound [N], status bits.
# Sigma bounds (the filter's own sigma, and the reported one): the steady-state 1-sigma of
# each mode on this log (IMU-only 464 N, a dead
# axle 352 N, full 187 N) rounded up; RMSE bounds: measured (26, 42, 33 N) with margin.
# A wheel without travel reports more: its sigma also grows with |ay - vx wz|, calibrated to
# cover an ay 0.5 s late (a real car's front-only reference log); on this lane change
# (ay on time) the sideslip rate takes it to 656 N on every mode with such a wheel.
REPORTED_WITHOUT_TRAVEL = 700.0
MODES = [
    ("imu-only", lambda f: f.drop(columns=TRAVEL), "IMU-only", 250.0, 60.0, 0),
    ("one per axle", lambda f: _dead(f, ("fr", "rr")), "two travel sensors, missing FR RR",
     250.0, 60.0, 0),
    ("front pair", lambda f: _dead(f, ("rl", "rr")), "two travel sensors, missing RL RR",
     400.0, 80.0, 0),
    ("dead corner", lambda f: _dead(f, ("rr",)), "one corner dead", 400.0, 80.0, 0),
    ("no az", lambda f: f.drop(columns=["az"]), "no az: g assumed", 200.0, 40.0,
     StepFlag.AZ_ASSUMED_G),
    ("no vx", lambda f: f.drop(columns=["vx"]), "aerodynamic terms off", 200.0, 60.0,
     StepFlag.AERO_OFF_NO_SPEED),
    ("vx from wheels", lambda f: f.drop(columns=["vx"]).assign(ws_rl=f.vx * 1.01,
                                                                ws_rr=f.vx * 0.99),
     "mean of the wheel speeds", 200.0, 40.0, StepFlag.SPEED_FROM_WHEELS),
]  # fmt: skip


@pytest.mark.parametrize(("name", "edit", "words", "sigma", "rmse", "bits"), MODES)
def test_partial_sensor_set(vehicle, plant_log, name, edit, words, sigma, rmse, bits):
    signals = signals_from_frame(edit(plant_log), source=name)
    estimate = TwoStageKF(vehicle).run(signals)
    assert np.isfinite(estimate.loads).all() and np.isfinite(estimate.std).all()
    without_travel = not signals.travel_present.all()
    assert estimate.std.max() <= (REPORTED_WITHOUT_TRAVEL if without_travel else sigma)
    # Bounded, not merely small on a short log: the filter's own sigma (sqrt P) in the last
    # second is no wider than in the first after the start-up transient (a random walk left
    # unobserved grows as sqrt(t)).
    own = TwoStageKF(vehicle)
    own.tuning = with_filter_sigma(own.tuning)
    own_std = own.run(signals).std
    assert own_std.max() <= sigma
    assert own_std[-100:].max() <= 1.01 * own_std[100:200].max()
    assert wheel_metrics(estimate.loads, signals.reference).loc["pooled", "RMSE"] <= rmse
    assert words in summary(estimate, signals, "car")
    if bits:
        assert np.all(estimate.flags & bits)
    if not np.isfinite(signals.d).any():
        assert not signals.velocities_derived
        assert "velocities derived" not in summary(estimate, signals, "car")


def test_one_sensor_per_axle_uses_the_roll_split_row(vehicle, plant_log):
    # The anti-roll-bar term of a corner needs the other side's travel, so one sensor per
    # axle gives no suspension row: the step falls back to the roll-split row, as IMU-only.
    signals = signals_from_frame(_dead(plant_log, ("fr", "rr")), source="pair")
    estimate = TwoStageKF(vehicle).run(signals)
    assert "roll-split row used: 100 %" in row_use(estimate)
    imu = TwoStageKF(vehicle).run(signals_from_frame(plant_log.drop(columns=TRAVEL)))
    np.testing.assert_allclose(estimate.loads, imu.loads, rtol=1e-12)


def _front_difference_error(vehicle, frame, split):
    suspension = dataclasses.replace(vehicle.suspension, roll_split_front=split)
    signals = signals_from_frame(frame.drop(columns=TRAVEL))
    estimate = TwoStageKF(vehicle.replace(suspension=suspension)).run(signals)
    estimated = estimate.loads[:, 0] - estimate.loads[:, 1]
    reference = signals.reference[:, 0] - signals.reference[:, 1]
    return np.sqrt(np.mean((estimated - reference) ** 2) / np.mean(reference**2))


def test_imu_only_front_lateral_transfer_with_the_right_split(vehicle, plant_log):
    # The plant's split: least squares of the front roll moment on the total one.
    reference = plant_log[[f"fz_{w}" for w in WHEELS]].to_numpy()
    front = 0.5 * vehicle.geometry.track_front * (reference[:, 0] - reference[:, 1])
    rear = 0.5 * vehicle.geometry.track_rear * (reference[:, 2] - reference[:, 3])
    total = front + rear
    split = float(np.sum(front * total) / np.sum(total * total))
    assert _front_difference_error(vehicle, plant_log, split) <= 0.15  # the 15 %
    # The default (roll stiffness of springs and bars with the roll-centre moments)
    # is that split here, to 0.01 ...
    default = TwoStageKF(vehicle).parameters.roll_split_front
    assert abs(default - split) < 0.01
    # ... and the row matters: a split 0.15 off misses the front transfer by more than 15 %.
    assert _front_difference_error(vehicle, plant_log, split - 0.15) > 0.15


def test_sensor_sets_command_prints_every_mode_and_the_sweep(capsys):
    from wheelload.studies.experiments.sensor_sets import MODES
    from wheelload.studies.pipeline.example_log import example_log_path

    assert main(["sensor-sets", str(example_log_path()), "--splits", "0.4"]) == 0
    text = capsys.readouterr().out
    assert all(name in text for name in MODES)
    assert "False" not in text  # every mode finite
    # Springs and bars alone: 0.4892; the links' roll-centre moments (geometric
    # transfer on in the bundled file) move the default to 0.4835.
    assert "roll split: default 0.4835 (springs, bars and roll centres)" in text
