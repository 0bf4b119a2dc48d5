"""Corner-based estimator (corner-based paper eq. 17-18): rigid-body statics, drift compensation."""

import numpy as np
import pytest

from wheelload.estimators.family.corner import CornerBased, CornerSettings
from wheelload.estimators.logs.signals import read_log
from wheelload.estimators.protocol import Estimator, SuspensionModel
from wheelload.estimators.samples import samples, step_through
from wheelload.estimators.types import Signals
from wheelload.models import (
    ModelParameters,
    example_vehicle_path,
    load_vehicle,
    paper_equilibrium_function,
)
from wheelload.models.body_attitude import roll_pitch_stiffness
from wheelload.studies.pipeline.example_log import example_log_path


def constant_log(acc, rates=(0.0, 0.0, 0.0), seconds=20.0):
    n = int(seconds / 0.01)
    return Signals(
        t=0.01 * np.arange(1, n + 1), vx=np.zeros(n), acc=np.tile(acc, (n, 1)),
        d=np.zeros((n, 4)), v=np.zeros((n, 4)), rates=np.tile(rates, (n, 1)),
    )  # fmt: skip


@pytest.mark.parametrize("ax", [-8.0, 0.0, 4.0])
def test_settled_loads_meet_rigid_body_equilibrium_in_the_pitched_frame(ax):
    """Steady braking / driving: vertical and pitch rows of the equilibrium model hold exactly
    with the specific force rotated by the stationary pitch of the pitch stiffness."""
    vehicle = load_vehicle(example_vehicle_path())
    az = 9.80665
    loads = (
        CornerBased(vehicle, suspension=SuspensionModel.PAPER)
        .run(constant_log([ax, 0.0, az]))
        .loads[-1]
    )
    k = roll_pitch_stiffness(vehicle)
    pitch = -vehicle.mass.sprung * vehicle.geometry.cg_height * ax / k.pitch
    rotated = [
        ax * np.cos(pitch) + az * np.sin(pitch),
        0.0,
        az * np.cos(pitch) - ax * np.sin(pitch),
    ]
    p = ModelParameters.from_vehicle(vehicle).vector()
    A, b = (np.asarray(m).ravel() if m.shape[1] == 1 else np.asarray(m) for m in
            paper_equilibrium_function()(rotated, 0.0, p))  # fmt: skip
    assert A @ loads == pytest.approx(b, abs=1e-6)  # N, N m
    assert loads[0] == pytest.approx(loads[1], abs=1e-9) and loads[2] == pytest.approx(loads[3])


def test_lateral_transfer_and_roll_centre_term():
    """A left turn loads the right wheels by m_i h a_y / T per axle; the roll-centre term
    moves load to the right by m_i a_z (h - h_rc) sin(phi) / T on top."""
    vehicle = load_vehicle(example_vehicle_path())
    ay, az = 5.0, 9.80665
    results = {}
    for h_rc in (0.0, 0.3):
        estimator = CornerBased(vehicle, CornerSettings(roll_centre_height=h_rc))
        results[h_rc] = estimator.run(constant_log([0.0, ay, az])).loads[-1]
    for loads in results.values():
        assert loads[1] > loads[0] and loads[3] > loads[2]
    # Same axle loads, different split: the roll-centre height changes only the split.
    for loads in results.values():
        assert loads[:2].sum() + loads[2:].sum() == pytest.approx(vehicle.mass.total * az, rel=1e-2)
    assert results[0.0][1] - results[0.0][0] != pytest.approx(results[0.3][1] - results[0.3][0])


def test_gyro_bias_leaves_a_bounded_angle_error():
    """Drift compensation: a 0.01 rad/s roll-rate bias settles at b / L, not an integral."""
    vehicle = load_vehicle(example_vehicle_path())
    estimator = CornerBased(vehicle, CornerSettings(observer_gain=2.0))
    signals = constant_log([0.0, 0.0, 9.80665], rates=(0.01, 0.0, 0.0), seconds=30.0)
    state = estimator.initial_state()
    for sample in samples(signals):
        state, _ = estimator.step(state, sample, 0.01)
    assert state[0][0] == pytest.approx(0.01 / 2.0, rel=1e-6)


def test_run_equals_steps_and_is_finite_on_the_example_log():
    estimator = CornerBased(load_vehicle(example_vehicle_path()))
    assert isinstance(estimator, Estimator)
    signals = read_log(example_log_path())
    run = estimator.run(signals)
    assert np.all(np.isfinite(run.loads)) and not run.has_std
    steps = step_through(estimator, signals.slice(0, 300))
    assert np.allclose(run.loads[:300], steps.loads, rtol=0, atol=1e-9)
