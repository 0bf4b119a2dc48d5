"""One log-preparation path: checks, static loads and payload reference in one order."""

import numpy as np
import pytest

from wheelload.estimators import read_log
from wheelload.estimators.logs.checks import check_wiring
from wheelload.models import GRAVITY, example_vehicle_path, load_vehicle
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.log_preparation import prepare_log
from wheelload.studies.pipeline.log_settings import EstimateSettings
from wheelload.studies.pipeline.measured_static import measured_static_loads


@pytest.fixture(scope="module")
def signals():
    return read_log(example_log_path(), wiring_checks=False).slice(0, 400)


def _prepare(signals, settings, read):
    vehicle = load_vehicle(settings.vehicle)

    def report():
        read.append("wiring")
        return check_wiring(signals.t, signals.vx, signals.acc, signals.d, signals.rates)

    return prepare_log(
        vehicle,
        settings,
        source=signals.source,
        wiring_report=report,
        checked_signals=lambda: signals,
        static_loads=lambda vehicle: measured_static_loads(signals, vehicle, settings),
        notes=("read",),
    )


def test_checks_then_static_loads_in_order(signals):
    settings = EstimateSettings(vehicle=example_vehicle_path(), corner_weights="410,420,360,365")
    read = []
    prepared = _prepare(signals, settings, read)
    assert read == ["wiring"]
    # read, wiring, plausibility, corner weights: in that order (no payload note: the
    # example's travel is measured from the file's reference state)
    assert len(prepared.notes) == 4 and prepared.notes[0] == "read"
    assert prepared.notes[3] == "static loads from corner weights 410,420,360,365 kg"
    expected = GRAVITY * np.array([410.0, 420.0, 360.0, 365.0])  # kg on the scales, N
    np.testing.assert_allclose(prepared.static, expected, rtol=1e-12)


def test_a_still_period_on_a_moving_log_is_refused(signals):
    settings = EstimateSettings(vehicle=example_vehicle_path(), still_period=0.5)
    with pytest.raises(ValueError, match="not a still period"):  # the example drives off
        _prepare(signals, settings, [])


def test_without_wiring_checks_the_report_is_not_read(signals):
    settings = EstimateSettings(vehicle=example_vehicle_path(), wiring_checks=False)
    read = []
    prepared = _prepare(signals, settings, read)
    assert read == [] and prepared.notes == ("read",) and prepared.static is None
