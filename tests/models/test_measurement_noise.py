"""Input-dependent measurement noise: the model Function, default bit-identity, C equals Python.

Tolerances: the Function against numpy to 1e-12 relative (the same arithmetic in
another order); the bundled files (densities 0) against a step built with the
paper's constant R bit for bit (r + 0 = r exactly); the generated C against
the Python run to 1e-9 relative (as ``test_codegen``: same operations, same
order); the fast step against the CasADi step bit for bit.
"""

import dataclasses

import casadi as ca
import numpy as np
import pytest
from c_parity import assert_c_equals_python, c_estimates, kf_program

from wheelload.estimators import Sample, read_log, write_log
from wheelload.estimators.codegen.kf import CodegenOptions, ParamMode
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.kf.step import step_function
from wheelload.estimators.kf.tuning import TUNED_DENSITIES, TUNING_INDEX, noise_densities
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.protocol import sample_intervals
from wheelload.models import INPUTS, example_vehicle_path, load_vehicle
from wheelload.models.measurement_noise import DENSITIES, INPUT_DENSITIES
from wheelload.models.measurement_noise import measurement_noise_function as noise_function
from wheelload.models.vehicle.file import add_values
from wheelload.models.vehicle.plausibility import check_vehicle_ranges
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

G = 9.80665
NOISY = {
    "suspension_noise_rate_density": 2.0e4,
    "suspension_noise_hub_density": 3.0,
    "constraint_noise_vertical_acceleration": 40.0,
    "constraint_noise_pitch_acceleration": 900.0,
    "constraint_noise_roll_acceleration": 600.0,
}


def noisy_vehicle(vehicle):
    """The vehicle with every input-dependent density non-zero (:data:`NOISY`)."""
    rows = ("vertical", "pitch", "roll")
    return vehicle.replace(
        filter=dataclasses.replace(
            vehicle.filter,
            suspension_noise_rate_density=NOISY["suspension_noise_rate_density"],
            suspension_noise_hub_density=NOISY["suspension_noise_hub_density"],
            constraint_noise_acceleration_density=tuple(
                NOISY[f"constraint_noise_{r}_acceleration"] for r in rows
            ),
        )
    )


def test_noise_function_equals_a_numpy_computation():
    rng = np.random.default_rng(4)
    function = noise_function()
    for hub_logged in (True, False):
        u = rng.normal(size=len(INPUTS))
        u[INPUTS.index("az")] = G + rng.normal()
        valid = np.ones(len(INPUTS))
        if not hub_logged:
            for w in ("fl", "fr", "rl", "rr"):
                valid[INPUTS.index(f"az_{w}")] = 0.0
                u[INPUTS.index(f"az_{w}")] = 0.0
        densities = rng.uniform(1.0, 100.0, len(DENSITIES))
        dt = 0.004
        R_s, R_c = (np.asarray(x).ravel() for x in function(u, valid, densities, dt))
        r = dict(zip(DENSITIES, densities, strict=True))
        ax, ay, az = (u[INPUTS.index(a)] for a in ("ax", "ay", "az"))
        for i, w in enumerate(("fl", "fr", "rl", "rr")):
            v, hub = u[INPUTS.index(f"v_{w}")], u[INPUTS.index(f"az_{w}")]
            hub_term = r["suspension_noise_hub_density"] * (hub - az) ** 2 if hub_logged else 0.0
            expected = (
                r["suspension_noise_density"] + r["suspension_noise_rate_density"] * v**2 + hub_term
            ) / dt
            assert R_s[i] == pytest.approx(expected, rel=1e-12)
        for j, (row, a) in enumerate(zip(("vertical", "pitch", "roll"), (az - G, ax, ay))):
            expected = (
                r[f"constraint_noise_{row}"] + r[f"constraint_noise_{row}_acceleration"] * a**2
            )
            assert R_c[j] == pytest.approx(expected / dt, rel=1e-12)


def constant_noise() -> ca.Function:
    """The paper's constant R (eq. 20-25), written here: R_s = r_s/dt I, R_c = diag(r_c)/dt."""
    u, valid = ca.SX.sym("u", len(INPUTS)), ca.SX.sym("u_valid", len(INPUTS))
    d, dt = ca.SX.sym("densities", len(DENSITIES)), ca.SX.sym("dt")
    return ca.Function(
        "constant_noise", [u, valid, d, dt], [ca.repmat(d[0] / dt, 4, 1), d[1:4] / dt]
    )


@pytest.mark.parametrize("name", ["sports_car.toml", "suv.toml"])
def test_bundled_files_give_the_constant_noise_filter_bit_for_bit(plant_log, name):
    vehicle = load_vehicle(example_vehicle_path().parent / name)
    assert np.all(noise_densities(vehicle)[-len(INPUT_DENSITIES) :] == 0)
    signals = plant_log("iso-dlc")
    new = TwoStageKF(vehicle).run(signals)
    paper = TwoStageKF(vehicle, step=step_function(measurement_noise=constant_noise())).run(signals)
    for field in ("loads", "std", "residual", "flags"):
        np.testing.assert_array_equal(getattr(new, field), getattr(paper, field), err_msg=field)
    # ... and the input-dependent densities do act when set: on the gain, so on the loads
    # and P (measured 6 N and 12 N in sqrt P, sports car; the reported sigma moves 0.5 N).
    noisy, noisy_P = TwoStageKF(noisy_vehicle(vehicle)).run_with_covariance(signals)
    _, new_P = TwoStageKF(vehicle).run_with_covariance(signals)
    assert np.max(np.abs(noisy.loads - new.loads)) > 1.0
    assert np.max(np.abs(np.diagonal(noisy_P - new_P, axis1=1, axis2=2))) > 1.0


def test_fast_step_equals_the_casadi_step_with_input_dependent_noise(vehicle, plant_log):
    """Bit for bit over a plant log with hub accelerometers on every other sample."""
    kf = TwoStageKF(noisy_vehicle(vehicle), sample_interval=0.01)
    signals = plant_log("iso-dlc")
    dt = sample_intervals(signals.t)
    state_f = state_r = kf.initial_state()
    for k in range(250):
        hub = np.full(4, 9.81) + 2.0 * np.sin(0.7 * k + np.arange(4)) if k % 2 else None
        sample = Sample(d=signals.d[k], v=signals.v[k], acc=signals.acc[k], vx=signals.vx[k],
                        hub=hub)  # fmt: skip
        (state_f, est_f), (state_r, est_r) = (
            kf.step(state_f, sample, dt[k]),
            kf.reference_step(state_r, sample, dt[k]),
        )
        for a, b in ((state_f.x, state_r.x), (state_f.P, state_r.P), (est_f.std, est_r.std)):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(est_f.flags, est_r.flags)


def test_tuning_vector_holds_the_densities_by_name(vehicle):
    noisy = noisy_vehicle(vehicle)
    tuning = TwoStageKF(noisy).tuning
    for name, value in NOISY.items():
        assert tuning[TUNING_INDEX[name]] == value
    assert list(noise_densities(noisy)[-len(INPUT_DENSITIES) :]) == list(NOISY.values())
    assert TUNED_DENSITIES[-len(INPUT_DENSITIES) :] == INPUT_DENSITIES


def test_vehicle_file_keys_are_optional_checked_and_written(vehicle, tmp_path, capsys):
    text = example_vehicle_path().read_text()
    changes = {
        ("filter", "suspension_noise_rate_density"): (2.0e4, "test"),
        ("filter", "constraint_noise_acceleration_density"): ([40.0, 900.0, 600.0], "test"),
    }
    path = tmp_path / "noisy.toml"
    path.write_text(add_values(text, changes))
    loaded = load_vehicle(path)
    assert loaded.filter.suspension_noise_rate_density == 2.0e4
    assert loaded.filter.constraint_noise_acceleration_density == (40.0, 900.0, 600.0)
    assert loaded.filter.suspension_noise_hub_density == 0.0
    assert not [issue for issue in check_vehicle_ranges(loaded) if "noise" in str(issue)]
    bad = tmp_path / "bad.toml"
    bad.write_text(add_values(text, {("filter", "suspension_noise_hub_density"): (-1.0, "x")}))
    with pytest.raises(ValueError, match="suspension_noise_hub_density"):
        load_vehicle(bad)
    huge = tmp_path / "huge.toml"
    huge.write_text(add_values(text, {("filter", "suspension_noise_rate_density"): (1e12, "x")}))
    with pytest.raises(ValueError, match="suspension_noise_rate_density"):
        load_vehicle(huge)


@pytest.fixture(scope="module")
def noisy_log(tmp_path_factory):
    """A 6 s noisy slalom with hub accelerometers (so that every noise term acts)."""
    vehicle = load_vehicle(example_vehicle_path())
    signals = synthetic_log(vehicle, slalom(duration=6.0), noise=SensorNoise(acceleration=0.05,
                            travel=0.0003), seed=5)  # fmt: skip
    t = signals.t
    hub = 9.81 + 4.0 * np.sin(2 * np.pi * 11.0 * t[:, None] + np.arange(4))
    path = tmp_path_factory.mktemp("noisy") / "drive.csv"
    write_log(dataclasses.replace(signals, hub=hub), path)
    return path


def test_generated_c_equals_python_with_input_dependent_noise(tmp_path, noisy_log):
    """The library with run-time parameters (the baked one folds the same expressions)."""
    mode = ParamMode.RUNTIME
    text = example_vehicle_path().read_text()
    rows = ("vertical", "pitch", "roll")
    changes = {
        ("filter", "suspension_noise_rate_density"): (NOISY["suspension_noise_rate_density"], ""),
        ("filter", "suspension_noise_hub_density"): (NOISY["suspension_noise_hub_density"], ""),
        ("filter", "constraint_noise_acceleration_density"): (
            [NOISY[f"constraint_noise_{r}_acceleration"] for r in rows],
            "",
        ),
    }
    path = tmp_path / "noisy.toml"
    path.write_text(add_values(text, changes))
    binary = kf_program(
        path, tmp_path / "c", CodegenOptions(precision=Precision.DOUBLE, params=mode)
    )
    c = c_estimates(binary, noisy_log, tmp_path / "c_estimates.csv")
    loaded = load_vehicle(path)
    python = TwoStageKF(loaded).run(read_log(noisy_log)).to_pandas()
    default = TwoStageKF(load_vehicle(example_vehicle_path())).run(read_log(noisy_log)).to_pandas()
    for column in ("fz_fl", "fz_rr", "fz_std_fl", "fz_std_rr"):
        expected = python[column].to_numpy()
        assert_c_equals_python(c[column], expected, rtol=1e-9, atol=1e-9 * np.max(expected))
    # The noise terms changed the filter (else the comparison shows nothing new).
    assert np.max(np.abs(python["fz_std_fl"] - default["fz_std_fl"])) > 1.0
    # A density set at run time equals the file with that density.
    overrides = ("suspension_noise_rate_density=0",)
    changed = c_estimates(binary, noisy_log, tmp_path / "changed.csv", *overrides)
    zero = loaded.replace(
        filter=dataclasses.replace(loaded.filter, suspension_noise_rate_density=0.0)
    )
    expected = TwoStageKF(zero).run(read_log(noisy_log)).to_pandas()
    assert_c_equals_python(changed["fz_fl"], expected["fz_fl"], rtol=1e-9, atol=1e-5)
    assert np.max(np.abs(expected["fz_fl"] - python["fz_fl"])) > 0.1  # the override acted


def test_shape_rules_of_the_tuning():
    """Blend along the log-parameter line, the ratios the folds agree on, the input's ratios."""
    from wheelload.estimators.identification.tuning import (
        agreed_ratios,
        blend,
        with_input_ratios,
    )

    index = {name: k for k, name in enumerate(TUNED_DENSITIES)}
    start = np.array([2.25e7, 625.0, 900.0, 3600.0, 2500.0, 0, 0, 0, 0, 0])
    fit = np.array([3e4, 1.0, 40.0, 300.0, 30.0, 50.0, 0, 0, 0, 0.1])
    np.testing.assert_array_equal(blend(start, fit, 0.0), start)
    np.testing.assert_allclose(blend(start, fit, 1.0), fit, rtol=1e-12)
    half = blend(start, fit, 0.5)
    assert half[0] == pytest.approx(np.sqrt(2.25e7 * 3e4), rel=1e-12)  # geometric
    assert half[index["suspension_noise_rate_density"]] == pytest.approx(25.0)  # from 0: linear
    # Two fold fits: q/r_s 3e4 and 5e4 agree (within 2x); the pitch row's 300 and 900 do not.
    other = fit.copy()
    other[index["process_noise_density"]] = 5e4
    other[index["constraint_noise_pitch"]] = 900.0
    agreed = agreed_ratios([fit, other, fit])
    assert "process_noise_density" in agreed and "constraint_noise_pitch" not in agreed
    assert "constraint_noise_roll" in agreed
    assert agreed_ratios([fit, other]) == ()  # one log: nothing to compare
    # The fit on all logs far from both fold fits (a poorly converged search): not taken.
    far = fit.copy()
    far[index["constraint_noise_roll"]] = 300.0
    assert "constraint_noise_roll" not in agreed_ratios([far, fit, other])
    shaped = with_input_ratios(start, fit, ("process_noise_density",))
    assert shaped[index["process_noise_density"]] == 3e4  # agreed: the fit's
    assert shaped[index["suspension_noise_density"]] == 1.0
    assert shaped[index["constraint_noise_roll"]] == pytest.approx(2500.0 / 625.0)  # input's
    # The roll row's input-dependent density moves with its constant density (30 -> 4).
    roll = index["constraint_noise_roll_acceleration"]
    assert shaped[roll] == pytest.approx(0.1 * 4.0 / 30.0)
