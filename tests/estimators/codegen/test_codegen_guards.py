"""The guards in the generated C: outliers, a stuck sensor and extreme tuning on a plant log.

The C library is generated from the same symbolic step as the Python
filter, compiled by gcc with the strict warning flags (warnings are errors)
and run as the example program on a CSV log. Double precision agrees with
the Python filter to 1e-9 relative and flag for flag (the same operations in
the same order); single precision carries about 7 digits, so its gate
decisions are compared on the outlier samples only.
"""

import re

import numpy as np
import pandas as pd
import pytest
from c_parity import assert_c_equals_python, c_estimates, kf_program

from wheelload.estimators import StepFlag, read_log, write_log
from wheelload.estimators.codegen.kf import CodegenOptions, ParamMode
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.experiments.faults import fault_injection as fi
from wheelload.studies.experiments.faults.fault_injection import pooled_rmse

LOADS = [f"fz_{w}" for w in ("fl", "fr", "rl", "rr")]
OUTLIERS = {300: ("ax", 50.0), 400: ("ay", 100.0), 500: ("d_fl", 0.29), 600: ("ax", 1e30)}
SPIKE_ROW = 700  # d_fl + 30 mm: in range, fails the innovation gate
STUCK_FROM = 900  # d_fl stuck from here on
DEAD_FROM = 1100  # d_rr falls to its rail (-75 mm) and freezes: dropped at once (TRAVEL_JUMP)


@pytest.fixture(scope="module")
def faulty_log(plant_log, tmp_path_factory):
    signals = plant_log("iso-dlc")
    frame = pd.DataFrame({"t": signals.t, "vx": signals.vx})
    for i, axis in enumerate(("ax", "ay", "az")):
        frame[axis] = signals.acc[:, i]
    for i, wheel in enumerate(("fl", "fr", "rl", "rr")):
        frame[f"d_{wheel}"] = signals.d[:, i]
        frame[f"v_{wheel}"] = signals.v[:, i]
        frame[f"fz_{wheel}"] = signals.reference[:, i]
    for row, (channel, value) in OUTLIERS.items():
        frame.loc[row, channel] = value
    frame.loc[SPIKE_ROW, "d_fl"] += 0.030
    frame.loc[STUCK_FROM:, "d_fl"] = frame.loc[STUCK_FROM - 1, "d_fl"]
    frame.loc[STUCK_FROM:, "v_fl"] = 0.0
    frame.loc[DEAD_FROM:, "d_rr"] = -0.075
    frame.loc[DEAD_FROM:, "v_rr"] = 0.0
    path = tmp_path_factory.mktemp("faulty") / "faulty.csv"
    frame.to_csv(path, index=False)
    return path


def run_c(vehicle_path, log_path, out_dir, precision, allow_unusual=False):
    options = CodegenOptions(precision=precision)
    binary = kf_program(vehicle_path, out_dir, options, allow_unusual=allow_unusual)
    return c_estimates(binary, log_path, out_dir / "estimates.csv")


def check_outlier_flags(flags):
    for row, (channel, _) in OUTLIERS.items():
        bit = (
            StepFlag.TRAVEL_IMPLAUSIBLE if channel == "d_fl" else StepFlag.ACCELERATION_IMPLAUSIBLE
        )
        assert flags[row] & bit
    assert flags[SPIKE_ROW] & StepFlag.INNOVATION_GATED
    assert flags[STUCK_FROM + 30] & StepFlag.TRAVEL_FAULT
    assert np.all(flags[DEAD_FROM:] & StepFlag.TRAVEL_JUMP)
    assert not np.any(flags[:DEAD_FROM] & StepFlag.TRAVEL_JUMP)


def test_double_c_guards_equal_python(vehicle, faulty_log, tmp_path):
    c = run_c(example_vehicle_path(), faulty_log, tmp_path, Precision.DOUBLE)
    signals = read_log(faulty_log)
    python = TwoStageKF(vehicle).run(signals)
    assert_c_equals_python(c[LOADS], python.loads, rtol=1e-9, atol=1e-6)
    np.testing.assert_array_equal(c["status"], python.flags)
    check_outlier_flags(c["status"].to_numpy())
    assert list(python.faults["channel"]) == ["d_fl", "d_rr"]
    unguarded = TwoStageKF(vehicle, guard_settings=fi.GUARDS_OFF).run(signals)
    assert pooled_rmse(c[LOADS].to_numpy(), signals.reference) < 100.0
    assert pooled_rmse(unguarded.loads, signals.reference) > 1000.0


def test_float_c_gates_the_same_outliers(vehicle, faulty_log, tmp_path):
    c = run_c(example_vehicle_path(), faulty_log, tmp_path, Precision.FLOAT)
    signals = read_log(faulty_log)
    python = TwoStageKF(vehicle).run(signals)
    check_outlier_flags(c["status"].to_numpy())
    rows = [*OUTLIERS, SPIKE_ROW, DEAD_FROM]
    np.testing.assert_array_equal(c["status"].to_numpy()[rows], python.flags[rows])
    assert (
        abs(
            pooled_rmse(c[LOADS].to_numpy(), signals.reference)
            - pooled_rmse(python.loads, signals.reference)
        )
        < 1.0
    )


def vehicle_file(tmp_path, **values):
    """The bundled vehicle file with [filter] values replaced."""
    text = example_vehicle_path().read_text(encoding="utf-8")
    for key, value in values.items():
        text, count = re.subn(rf"(?m)^{key} = .*$", f"{key} = {value!r}", text)
        assert count == 1
    path = tmp_path / "extreme.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("precision", [Precision.FLOAT, Precision.DOUBLE])
@pytest.mark.parametrize(
    "tuning", [{"initial_std": 1.2e6}, {"initial_std": 1e200}, {"process_noise_density": 1e300}]
)
def test_extreme_tuning_never_kills_the_c_filter(plant_log, tmp_path, precision, tuning):
    """Issue 8: a diagonal <= 0 after one step used to reject that step and every later one."""
    path = vehicle_file(tmp_path, **tuning)
    signals = plant_log("iso-dlc")
    log = tmp_path / "dlc.csv"
    write_log(signals, log)
    # such a tuning is outside the vehicle file's plausible ranges: --allow-unusual
    c = run_c(path, log, tmp_path, precision, allow_unusual=True)
    flags = c["status"].to_numpy()
    assert np.isfinite(c[LOADS].to_numpy()).all()
    assert not np.any(flags & StepFlag.STEP_REJECTED)
    # The log has no rate derivatives: the C example estimates them as Python does.
    logged = read_log(log)
    python = TwoStageKF(load_vehicle(path, allow_unusual=True)).run(logged)
    assert pooled_rmse(c[LOADS].to_numpy(), signals.reference) < 250.0
    if precision is Precision.DOUBLE:
        assert_c_equals_python(c[LOADS], python.loads, rtol=1e-9, atol=1e-6)


def test_codegen_options_reject_a_bad_sample_interval():
    with pytest.raises(ValueError, match="sample interval"):
        CodegenOptions(sample_interval=0.0)
    assert ParamMode.RUNTIME is CodegenOptions().params
