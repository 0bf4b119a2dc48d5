"""Identification on the plant's rig sweeps: rates, damper slopes, errors, outliers, warnings.

The rig drives the plant's own force elements (``studies/drive/rig.py``): the
spring and bar are linear there, so their rates come back to 3 % (the
issue's bound; load-cell noise alone leaves < 0.5 %). The plant's damper is a
two-slope map, so the linear fit is compared with the least-squares slope of
that map over the same velocities (an independent numpy fit), to 5 %.
"""

import casadi as ca
import numpy as np
import pytest

from wheelload.estimators.identification import (
    DataKind,
    DataSet,
    FitLoss,
    FitSettings,
    SuspensionFitModel,
    default_model,
    identify,
    piecewise_model,
    read_rig,
)
from wheelload.estimators.identification.model import TRAVEL, TRAVEL_RATE
from wheelload.estimators.identification.regressors import prediction
from wheelload.models import ModelParameters, travel_function
from wheelload.models.conventions import WHEELS
from wheelload.models.plant.dynamics import damper_map_force
from wheelload.studies.drive.rig import RigSettings, rig_sweep, write_rig


@pytest.fixture(scope="module")
def rig_sets(vehicle, tmp_path_factory):
    corner, bar = rig_sweep(vehicle, RigSettings(duration=10.0))
    corner_path, bar_path = write_rig(corner, bar, tmp_path_factory.mktemp("rig") / "rig.csv")
    return read_rig(corner_path) + read_rig(bar_path)


@pytest.fixture(scope="module")
def parameters(vehicle):
    return ModelParameters.from_vehicle(vehicle)


def plant_map_slope(damper, velocities):
    """Least-squares slope through the origin of the plant's damper map over ``velocities``."""
    v = ca.SX.sym("v")
    force = ca.Function("map", [v], [damper_map_force(v, damper)])
    f = np.asarray(force.map(velocities.size)(velocities)).ravel()
    return float(velocities @ f / (velocities @ velocities))


def test_rig_round_trip_recovers_rates_and_damper_slopes(vehicle, rig_sets, parameters):
    result = identify(default_model(), rig_sets, parameters)
    assert result.warnings == ()
    for axle in ("front", "rear"):
        setting = getattr(vehicle.suspension, axle)
        assert result.value_of(f"spring_{axle}") == pytest.approx(setting.spring_rate, rel=0.03)
        assert result.value_of(f"arb_rate_{axle}") == pytest.approx(setting.arb_rate, rel=0.03)
        damper = getattr(vehicle.plant.dampers, axle)
        corner = [s for s in rig_sets if s.rows[0] == ("fl" if axle == "front" else "rl")][0]
        v = corner.signals["v"].ravel()
        push, pull = plant_map_slope(damper, v[v > 0]), plant_map_slope(damper, v[v < 0])
        assert result.value_of(f"damper_push_{axle}") == pytest.approx(push, rel=0.05)
        assert result.value_of(f"damper_pull_{axle}") == pytest.approx(pull, rel=0.05)
        # The bundled file's slopes are the maps' 0.1 m/s secants: far from the fitted range.
        assert abs(push - setting.damper_push) > 0.2 * setting.damper_push
    assert np.all(np.isfinite(result.std_error[list(result.free)]))
    assert np.allclose(np.diag(result.correlation), 1.0)


def test_piecewise_damper_recovers_the_plant_map_segments(vehicle, rig_sets, parameters):
    """Knot at the map's first point (0.1 m/s): the segment slopes are the map's, to 1 %."""
    result = identify(piecewise_model((0.1,)), rig_sets, parameters)
    for axle in ("front", "rear"):
        damper = getattr(vehicle.plant.dampers, axle)
        (v1, v2) = damper.velocities
        for side in ("push", "pull"):
            f1, f2 = getattr(damper, side)
            assert result.value_of(f"damper_{side}_{axle}_0") == pytest.approx(f1 / v1, rel=0.01)
            assert result.value_of(f"damper_{side}_{axle}_1") == pytest.approx(
                (f2 - f1) / (v2 - v1), rel=0.01
            )


def rig_data(vehicle, folder, duration):
    corner, bar = rig_sweep(vehicle, RigSettings(duration=duration, seed=int(duration)))
    corner_path, bar_path = write_rig(corner, bar, folder / f"rig_{duration:.0f}.csv")
    return read_rig(corner_path) + read_rig(bar_path)


def test_standard_errors_shrink_as_one_over_root_n(vehicle, parameters, tmp_path):
    """Four times the record (5 s and 20 s sweeps): standard errors halve (1.6-2.5 allowed).

    The piecewise model matches the plant's map, so the residual is the white
    load-cell noise; with the linear damper the residual is the map mismatch,
    correlated in time, and the AR(1) correction keeps the errors from
    shrinking with denser sampling of the same sweep.
    """
    model = piecewise_model((0.1,))
    short = identify(model, rig_data(vehicle, tmp_path, 5.0), parameters)
    long = identify(model, rig_data(vehicle, tmp_path, 20.0), parameters)
    ratio = short.std_error[list(long.free)] / long.std_error[list(long.free)]
    assert np.all((ratio > 1.6) & (ratio < 2.5)), ratio


def corrupted(sets, fraction=0.05, seed=3):
    """Each set with ``fraction`` of its forces replaced by uniform outliers in ±4 kN."""
    rng = np.random.default_rng(seed)
    out = []
    for data in sets:
        target = data.target.copy()
        index = rng.choice(len(data), int(fraction * len(data)), replace=False)
        target[index, 0] = rng.uniform(-4000.0, 4000.0, index.size)
        out.append(data.with_target(target))
    return tuple(out)


def within_bounds(result, vehicle):
    errors = []
    for axle in ("front", "rear"):
        setting = getattr(vehicle.suspension, axle)
        errors.append(abs(result.value_of(f"spring_{axle}") / setting.spring_rate - 1) / 0.03)
        errors.append(abs(result.value_of(f"arb_rate_{axle}") / setting.arb_rate - 1) / 0.03)
    return max(errors) <= 1.0


@pytest.mark.parametrize("loss", [FitLoss.HUBER, FitLoss.SOFT_L1])
def test_robust_fit_survives_outliers_that_break_least_squares(vehicle, rig_sets, parameters, loss):
    bad = corrupted(rig_sets)
    plain = identify(default_model(), bad, parameters)
    robust = identify(default_model(), bad, parameters, FitSettings(loss=loss))
    assert not within_bounds(plain, vehicle)
    assert within_bounds(robust, vehicle)


def test_no_rebound_data_warns_and_holds_the_pull_slope(rig_sets, parameters):
    push_only = tuple(
        s.subset(np.flatnonzero(s.signals["v"].ravel() >= 0)) if "v" in s.signals else s
        for s in rig_sets
    )
    result = identify(default_model(), push_only, parameters)
    named = " ".join(result.warnings)
    for name in ("damper_pull_front", "damper_pull_rear"):
        assert f"'{name}' is not excited" in named
        assert result.value_of(name) == result.initial[result.names.index(name)]
    assert "damper_push_front" not in named


def test_fixed_parameters_keep_the_file_value(rig_sets, parameters):
    result = identify(
        default_model(), rig_sets, parameters, FitSettings(fixed=frozenset({"spring_front"}))
    )
    assert result.value_of("spring_front") == parameters.spring_front
    assert "spring_front" in result.held
    with pytest.raises(ValueError, match="no model parameter 'sprung_front'"):
        identify(
            default_model(), rig_sets, parameters, FitSettings(fixed=frozenset({"sprung_front"}))
        )


def progressive_spring_model():
    """A variant model: the bundled one plus a progressive spring term 20 k d^2 per wheel."""
    d, v = ca.SX.sym("d", 4), ca.SX.sym("v", 4)
    p_vector, p = ModelParameters.symbolic()
    springs = ca.vertcat(p.spring_front, p.spring_front, p.spring_rear, p.spring_rear)
    z = travel_function()(d, v, p_vector) + 20.0 * springs * d**2
    function = ca.Function("suspension_progressive", [d, v, p_vector], [z], ["d", "v", "p"], ["z"])
    return SuspensionFitModel(
        function=function,
        parameters={"p": ModelParameters.names()},
        channels={"d": TRAVEL, "v": TRAVEL_RATE},
    )


def test_a_changed_model_changes_the_identification(rig_sets, parameters):
    """Forces generated by the variant: the variant recovers the rates, the bundled model not.

    No identification code changes between the two fits: only the model Function.
    """
    variant = progressive_spring_model()
    truth = parameters.vector() * np.where(
        np.isin(ModelParameters.names(), ["spring_front", "spring_rear"]), 1.1, 1.0
    )
    sets = []
    for data in rig_sets:
        pred = prediction(variant, data)
        s = np.hstack([data.signals[c] for c in pred.columns])
        sets.append(data.with_target(np.asarray(pred.function.map(len(data))(s.T, truth)).T))
    fitted = identify(variant, tuple(sets), parameters)
    bundled = identify(default_model(), tuple(sets), parameters)
    for name in ("spring_front", "spring_rear"):
        j = ModelParameters.names().index(name)
        assert fitted.value_of(name) == pytest.approx(truth[j], rel=1e-6)
        assert abs(bundled.value_of(name) / truth[j] - 1) > 0.002


def stacked_input_model():
    """A variant in the layout of a stacked input vector ``u = [d, v, ax, ay, az, vx]`` with a
    new linear term: a link load :math:`\\mp 800\\, a_y h` per side (``h = cg_height``)."""
    u = ca.SX.sym("u", 12)
    p_vector, p = ModelParameters.symbolic()
    side = ca.DM([-1.0, 1.0, -1.0, 1.0])
    z = travel_function()(u[0:4], u[4:8], p_vector) + side * 800.0 * u[9] * p.cg_height
    function = ca.Function("suspension_links", [u, p_vector], [z], ["u", "p"], ["z"])
    return SuspensionFitModel(
        function=function,
        parameters={"p": ModelParameters.names()},
        channels={"u": TRAVEL + TRAVEL_RATE + ("ax", "ay", "az", "vx")},
    )


def test_a_new_input_layout_and_term_flow_into_the_identification(rig_sets, parameters):
    """Drive data made by the variant: its new parameter (and the rates) come back exactly;
    the identification code is the same, only the model Function and its input names differ."""
    variant = stacked_input_model()
    rng = np.random.default_rng(5)
    n = 3000
    channels = {name: rng.normal(0.0, 0.01, (n, 1)) for name in variant.channel_names()}
    channels["ay"] = rng.normal(0.0, 4.0, (n, 1))
    names = ModelParameters.names()
    truth = parameters.vector() * np.where(np.isin(names, ["cg_height"]), 1.3, 1.0)
    drive = DataSet(
        kind=DataKind.DRIVE,
        source="synthetic",
        t=np.arange(n) / 100.0,
        signals=channels,
        target=np.zeros((n, 4)),
        rows=("fl", "fr", "rl", "rr"),
    )
    pred = prediction(variant, drive)
    s = np.hstack([channels[c] for c in pred.columns])
    drive = drive.with_target(np.asarray(pred.function.map(n)(s.T, truth)).T)
    fitted = identify(variant, (*rig_sets, drive), parameters)
    assert fitted.value_of("cg_height") == pytest.approx(truth[names.index("cg_height")], rel=1e-3)
    assert fitted.sources["cg_height"] == ("synthetic",)
    assert fitted.value_of("spring_rear") == pytest.approx(parameters.spring_rear, rel=0.03)
    bundled = identify(default_model(), (*rig_sets, drive), parameters)
    assert "cg_height" not in bundled.sources
    assert bundled.value_of("cg_height") == parameters.cg_height


def noisy_drive_log(parameters, seed=5):
    """A drive data set from the paper's model (springs, push/pull dampers, bars) whose travel
    rates are backward differences of noisy travels, as a logger derives them: travel noise
    0.02 mm white at 100 Hz, so rate noise 0.003 m/s against rates of about 0.01 m/s (the
    plant's accel-in-turn log: 0.003 against 0.005 m/s)."""
    rng = np.random.default_rng(seed)
    model = default_model()
    dt, n = 0.01, 6000
    t = dt * np.arange(n)
    d_true, v_true = np.zeros((n, 4)), np.zeros((n, 4))
    for i in range(4):
        for frequency in rng.uniform(0.3, 2.0, 3):
            amplitude, phase = rng.uniform(4e-4, 1.2e-3), rng.uniform(0, 2 * np.pi)
            d_true[:, i] += amplitude * np.sin(2 * np.pi * frequency * t + phase)
            v_true[:, i] += (
                amplitude * 2 * np.pi * frequency * np.cos(2 * np.pi * frequency * t + phase)
            )
    error = 2e-5 * rng.standard_normal((n, 4))
    d = d_true + error
    v = v_true + np.diff(error, axis=0, prepend=error[:1]) / dt

    def signals(travel, rate):
        table = {name: np.zeros((n, 1)) for name in model.channel_names()}
        for i in range(4):
            table[TRAVEL[i]], table[TRAVEL_RATE[i]] = travel[:, i, None], rate[:, i, None]
        return table

    clean = signals(d_true, v_true)
    pred = prediction(model, DataSet(kind=DataKind.DRIVE, source="x", t=t, signals=clean,
                                     target=np.zeros((n, 4)), rows=WHEELS))  # fmt: skip
    s = np.hstack([clean[name] for name in pred.columns])
    loads = np.asarray(pred.function.map(n)(s.T, parameters.vector())).T
    target = loads + 5.0 * rng.standard_normal((n, 4))  # load-transducer noise [N]
    return DataSet(kind=DataKind.DRIVE, source="noisy.csv", t=t, signals=signals(d, v),
                   target=target, rows=WHEELS)  # fmt: skip


def test_instruments_remove_the_bias_that_rate_noise_gives_the_damper_slopes(parameters):
    """Noise in a regressor biases least squares towards zero by var(v) / (var(v) +
    var(noise)); two-stage least squares with the samples two steps away as instruments
    (their noise is independent) recovers the slopes. Measured: plain -10 to -16 %,
    instrumented -3.0 to +2.0 % (standard errors 0.8-1.5 %; what is left comes from the
    push/pull switch, which the noisy rate's sign sets). Tolerance 4 %."""
    data = (noisy_drive_log(parameters),)
    truth = dict(zip(ModelParameters.names(), parameters.vector()))
    plain = identify(default_model(), data, parameters)
    instrumented = identify(default_model(), data, parameters, FitSettings(instrumental=True))
    for name in ("damper_push_front", "damper_pull_front", "damper_push_rear", "damper_pull_rear"):
        assert plain.value_of(name) < 0.92 * truth[name]
        assert instrumented.value_of(name) == pytest.approx(truth[name], rel=0.04)
    for name in ("spring_front", "spring_rear", "arb_rate_front", "arb_rate_rear"):
        assert instrumented.value_of(name) == pytest.approx(truth[name], rel=0.03)
