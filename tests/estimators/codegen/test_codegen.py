"""Generated C library: compiled with gcc and strict warnings, run on a log, compared with Python.

Tolerances: the double build evaluates the same operations in the same order
as the Python filter's compiled step, so it agrees to 1e-9 relative (a
margin of about 1e6 over rounding). The float build carries about 7
significant digits on loads of about 4 kN; its error stays within 0.5 N.
"""

import dataclasses
import hashlib

import casadi as ca
import numpy as np
import pandas as pd
import pytest
from c_parity import assert_c_equals_python, c_estimates, compile_program, kf_library, run_program

from wheelload.estimators import StepFlag, read_log, signals_from_frame, write_log
from wheelload.estimators.codegen.kf import (
    CodegenOptions,
    ParamMode,
    calibration_names,
)
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.kf.step import step_function
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.signals import rate_derivatives
from wheelload.estimators.result import MASS_PROPERTY_COLUMNS, RESIDUALS, WHEELS
from wheelload.models import INPUTS, example_vehicle_path, suspension_function
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

pytestmark = pytest.mark.heavy(28)  # seconds (tests/conftest.py)

LOADS = [f"fz_{w}" for w in WHEELS]
STD = [f"fz_std_{w}" for w in WHEELS]


def run_example(library, log_path):
    """The library's example program, built by the real gcc with the strict warning flags
    (warnings as errors), on the log at ``log_path``."""
    binary = compile_program(library, library.example, "example")
    out = log_path.parent / f"{library.header.parent.name}_estimates.csv"
    return c_estimates(binary, log_path, out)


def with_optional_channels(signals, rng):
    """Body rates, their derivative and hub accelerometers, so that every model term runs.

    Smooth signals of the slalom's frequencies (the C is compared with Python,
    not with a plant); 2 % of their samples missing (the terms then drop).
    """
    t = signals.t
    w = 2 * np.pi * 0.4
    # Yaw rate of the slalom's own lateral acceleration (wz = ay / vx), so that
    # the log passes the reader's wiring checks (vx wz : ay = 1).
    yaw = signals.acc[:, 1] / signals.vx
    rates = np.column_stack([-0.05 * np.cos(w * t), 0.02 * np.sin(w * t), yaw])
    rate_dots = np.column_stack([0.05 * w * np.sin(w * t), 0.02 * w * np.cos(w * t),
                                 np.gradient(yaw, t)])  # fmt: skip
    hub = 9.81 + 3.0 * np.sin(2 * np.pi * 11.0 * t[:, None] + np.arange(4))
    for array in (rates, rate_dots, hub):
        rows = rng.choice(len(t), size=len(t) // 50, replace=False)
        array[rows, rng.integers(array.shape[1], size=rows.size)] = np.nan
    return dataclasses.replace(signals, rates=rates, rate_dots=rate_dots, hub=hub)


@pytest.fixture(scope="module")
def log_path(vehicle, tmp_path_factory):
    """12 s slalom at 100 Hz with sensor noise and 2 % missing samples in random channels.

    With body rates, their derivative and hub accelerometers, and a travel
    into the bump stop, so that every model term of the vehicle file runs.
    """
    signals = synthetic_log(
        vehicle,
        slalom(duration=12.0),
        noise=SensorNoise(acceleration=0.05, travel=0.0003),
        spring_error=0.08,
        seed=3,
    )
    rng = np.random.default_rng(7)
    d, v, acc, vx = signals.d.copy(), signals.v.copy(), signals.acc.copy(), signals.vx.copy()
    for row in rng.choice(len(signals), size=len(signals) // 50, replace=False):
        channel = rng.integers(12)
        target = d if channel < 4 else v if channel < 8 else acc if channel < 11 else None
        if target is None:
            vx[row] = np.nan
        else:
            target[row, channel % 4 if channel < 8 else channel - 8] = np.nan
    d[300:310, 0] = 0.03 + 0.002 * np.arange(10)  # past the front bump-stop gap (26 mm)
    signals = dataclasses.replace(signals, d=d, v=v, acc=acc, vx=vx)
    signals = with_optional_channels(signals, rng)
    path = tmp_path_factory.mktemp("log") / "drive.csv"
    write_log(signals, path)
    return path


@pytest.fixture(scope="module")
def python_estimates(vehicle, log_path):
    return TwoStageKF(vehicle).run(read_log(log_path)).to_pandas()


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """``generated(precision, mode, step=None, name="lib")``: the library of the example
    vehicle, generated once per precision and parameter mode in this module (the same
    files every time); a step of the test's own is generated for its call alone."""
    made = {}

    def generate_once(precision, mode, step=None, name="lib"):
        if step is None and (precision, mode) in made:
            return made[precision, mode]
        out = tmp_path_factory.mktemp(f"{name}_{precision.value}_{mode.value}")
        options = CodegenOptions(precision=precision, params=mode)
        library = kf_library(example_vehicle_path(), out, options, step=step)
        if step is None:
            made[precision, mode] = library
        return library

    return generate_once


def assert_double_build_matches(c, python):
    """The double build's columns against the Python run's (module docstring's tolerance);
    the online mass properties too: the payload filter's state rides in the monitor."""
    assert list(c.columns) == list(python.columns)
    for column in [*LOADS, *STD, *RESIDUALS, *MASS_PROPERTY_COLUMNS]:
        expected = python[column].to_numpy()
        scale = np.max(np.abs(expected))
        assert_c_equals_python(c[column], expected, rtol=1e-9, atol=1e-9 * scale, what=column)
    np.testing.assert_array_equal(c["status"], python["status"])


@pytest.mark.parametrize("mode", list(ParamMode))
def test_double_build_matches_python_run(generated, log_path, python_estimates, mode):
    c = run_example(generated(Precision.DOUBLE, mode), log_path)
    assert_double_build_matches(c, python_estimates)
    assert (python_estimates["status"] != 0).sum() > 10  # the guarding was exercised


@pytest.mark.parametrize("mode", list(ParamMode))
def test_float_build_matches_python_run(generated, log_path, python_estimates, mode):
    c = run_example(generated(Precision.FLOAT, mode), log_path)
    loads = c[LOADS].to_numpy() - python_estimates[LOADS].to_numpy()
    assert np.max(np.abs(loads)) < 0.5
    std = c[STD].to_numpy() - python_estimates[STD].to_numpy()
    assert np.max(np.abs(std)) < 0.05  # std depends on P only, not on the signals
    np.testing.assert_array_equal(c["status"], python_estimates["status"])


@pytest.fixture(scope="module")
def imu_only_log_path(tmp_path_factory):
    """A plant brake-in-turn log (sensor noise s = 1) with every travel sample missing.

    The rate derivatives are written into the log: the C example reads them,
    the Python reader would derive them.
    """
    log = run_scenario("brake-in-turn", example_vehicle_path()).log
    travel = [f"{kind}_{w}" for kind in ("d", "v") for w in WHEELS]
    signals = signals_from_frame(log.assign(**{name: np.nan for name in travel}))
    signals = dataclasses.replace(signals, rate_dots=rate_derivatives(signals))
    path = tmp_path_factory.mktemp("imu_only") / "imu_only.csv"
    write_log(signals, path)
    return path


def test_double_build_matches_python_run_without_travel(vehicle, generated,
                                                        imu_only_log_path):  # fmt: skip
    # IMU-only: the road frame takes its attitude from the equilibrium in every sample,
    # and the roll-split row observes the warp; same tolerance as with travel.
    c = run_example(generated(Precision.DOUBLE, ParamMode.BAKED),
                    imu_only_log_path)  # fmt: skip
    python = TwoStageKF(vehicle).run(read_log(imu_only_log_path)).to_pandas()
    assert_double_build_matches(c, python)
    assert (python["status"].to_numpy() & int(StepFlag.ROAD_FRAME_OR_LINKS_DROPPED)).all()


def test_header_traces_the_vehicle_file_and_model(generated):
    library = generated(Precision.FLOAT, ParamMode.RUNTIME)
    header = library.header.read_text()
    vehicle_hash = hashlib.sha256(example_vehicle_path().read_bytes()).hexdigest()
    model_hash = hashlib.sha256(step_function().serialize().encode()).hexdigest()
    assert f'WHEELLOAD_KF_VEHICLE_SHA256 "{vehicle_hash}"' in header
    assert f'WHEELLOAD_KF_MODEL_SHA256 "{model_hash}"' in header
    for name in calibration_names():
        assert f"wheelload_kf_real {name};" in header
    for flag in StepFlag:
        assert f"WHEELLOAD_KF_FLAG_{flag.name} {flag.value}u" in header
    binary = compile_program(library, library.example, "example")
    assert vehicle_hash.encode() in binary.read_bytes()
    source = library.source.read_text()
    for forbidden in ("malloc", "printf", "double"):
        assert forbidden not in source, forbidden


def quadratic_damper_suspension():
    """A variant model: the bundled suspension plus a quadratic damper term 800 v|v|."""
    base = suspension_function()
    u, gates = ca.SX.sym("u", base.size1_in(0)), ca.SX.sym("gates", base.size1_in(1))
    p = ca.SX.sym("p", base.size1_in(2))
    v = u[INPUTS.index("v_fl") : INPUTS.index("v_rr") + 1]
    z = base(u, gates, p) + 800.0 * v * ca.fabs(v)
    return ca.Function(
        "suspension_quadratic_damper", [u, gates, p], [z], ["u", "gates", "p"], ["z"]
    )


def test_changed_damper_model_changes_the_c(vehicle, generated, log_path):
    variant = step_function(suspension=quadratic_damper_suspension())
    base = generated(Precision.DOUBLE, ParamMode.RUNTIME)
    other = generated(Precision.DOUBLE, ParamMode.RUNTIME, variant, "variant")
    # The quadratic damper adds fabs(v) terms (the guards' range checks use fabs too).
    assert other.source.read_text().count("fabs(") > base.source.read_text().count("fabs(")
    c = run_example(other, log_path)
    expected = TwoStageKF(vehicle, step=variant).run(read_log(log_path)).to_pandas()
    default = TwoStageKF(vehicle).run(read_log(log_path)).to_pandas()
    assert np.max(np.abs(expected[LOADS].to_numpy() - default[LOADS].to_numpy())) > 1.0
    assert_c_equals_python(c[LOADS], expected[LOADS], rtol=1e-9, atol=1e-5)


def test_float_build_long_run_stays_finite_and_positive_definite(generated):
    """4 million steps (11 h at 100 Hz) of a repeated 20 s scenario; P is checked by
    Cholesky after every step. Bounded by the count, never by the clock."""
    library = generated(Precision.FLOAT, ParamMode.RUNTIME)
    binary = compile_program(library, library.selftest, "selftest")
    result = run_program(binary, "check", "4000000", check=False)
    report = dict(zip(*[iter(result.stdout.split())] * 2))
    assert result.returncode == 0, result.stdout
    assert report["steps"] == "4000000"
    assert report["nonfinite"] == report["indefinite"] == report["rejected"] == "0"
    assert int(report["flagged"]) > 40_000  # one missing input every 97 samples


def test_runtime_params_change_the_filter_without_regenerating(vehicle, generated, log_path):
    """Spring rate and roll-constraint noise set at run time equal a regenerated vehicle file."""
    library = generated(Precision.DOUBLE, ParamMode.RUNTIME)
    binary = compile_program(library, library.example, "example")
    out = library.header.parent / "overridden.csv"
    c = c_estimates(binary, log_path, out, "spring_front=66000", "constraint_noise_roll=5000")
    front = dataclasses.replace(vehicle.suspension.front, spring_rate=66000.0)
    noise = (*vehicle.filter.constraint_noise_density[:2], 5000.0)
    # The derived roll split follows the spring (wheelload_kf_set_param), as in Python.
    changed = vehicle.replace(
        suspension=dataclasses.replace(vehicle.suspension, front=front),
        filter=dataclasses.replace(vehicle.filter, constraint_noise_density=noise),
    )
    expected = TwoStageKF(changed).run(read_log(log_path)).to_pandas()
    default = TwoStageKF(vehicle).run(read_log(log_path)).to_pandas()
    assert np.max(np.abs(expected[LOADS].to_numpy() - default[LOADS].to_numpy())) > 1.0
    assert_c_equals_python(c[LOADS], expected[LOADS], rtol=1e-9, atol=1e-5)


STEP_DRIVER = r"""
#include "wheelload_kf.h"

#include <stdio.h>

/* Rows of dt and the inputs (order of wheelload_kf_input_names) on stdin; loads and flags out. */
int main(void)
{
    wheelload_kf_state state;
    wheelload_kf_output out;
    wheelload_kf_input in;
    double dt, x;
    int k;
    if (wheelload_kf_init(&state, &wheelload_kf_default_params) != 0) {
        return 1;
    }
    while (scanf("%lf", &dt) == 1) {
        for (k = 0; k < WHEELLOAD_KF_N_INPUTS; ++k) {
            if (scanf("%lf", &x) != 1) {
                return 1;
            }
            *wheelload_kf_input_field(&in, k) = (wheelload_kf_real)x;
        }
        wheelload_kf_step(&state, &wheelload_kf_default_params, &in, (wheelload_kf_real)dt, &out);
        for (k = 0; k < 4; ++k) {
            printf("%.9g ", (double)out.loads[k]);
        }
        printf("%lu\n", (unsigned long)out.flags);
    }
    return 0;
}
"""


def test_bad_inputs_skip_updates_and_bad_intervals_hold_the_state(generated, log_path):
    """Inf skips the updates it feeds; a repeated time stamp (dt = 0) is rejected, state held.

    Driven through the library's step directly: the example program refuses
    such a log (see test_codegen_example.py).
    """
    frame = pd.read_csv(log_path).iloc[:200].copy()
    frame.loc[50, "az"] = np.inf
    frame.loc[120, "t"] = frame.loc[119, "t"]
    t = frame["t"].to_numpy()
    dt = np.diff(t, prepend=2 * t[0] - t[1])  # the first interval is t[1] - t[0]
    rows = np.column_stack([dt, frame[list(INPUTS)].to_numpy()])
    library = generated(Precision.FLOAT, ParamMode.BAKED)
    driver = library.header.parent / "step_driver.c"
    driver.write_text(STEP_DRIVER)
    binary = compile_program(library, driver, "step_driver")
    stdin = "\n".join(" ".join(repr(float(value)) for value in row) for row in rows)
    result = run_program(binary, stdin=stdin)
    c = np.loadtxt(result.stdout.splitlines())
    loads, flags = c[:, :4], c[:, 4].astype(int)
    assert len(c) == 200 and np.isfinite(loads).all()
    # A missing az skips the vertical row; the road frame and link loads, which
    # need every axis, are dropped for the sample and flagged.
    assert flags[50] & 0xFF == StepFlag.VERTICAL_SKIPPED
    assert flags[50] & StepFlag.ROAD_FRAME_OR_LINKS_DROPPED
    # A rejected step sets every update and dropped-term bit (the input bits
    # 20-22 are set by the Python reader only, never by the C).
    assert flags[120] == sum(StepFlag.update_flags()) | StepFlag.STEP_REJECTED
    np.testing.assert_array_equal(loads[120], loads[119])
