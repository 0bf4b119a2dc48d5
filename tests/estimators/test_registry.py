"""The registry names every method once; each registered method meets the Estimator protocol."""

import numpy as np
import pytest

from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.signals import read_log
from wheelload.estimators.protocol import Estimator, MethodInfo
from wheelload.estimators.registry import (
    FAMILY_MODULES,
    UnknownMethodError,
    UnknownOptionError,
    build,
    method,
    methods,
    tyre_methods,
)
from wheelload.estimators.samples import step_through
from wheelload.studies.pipeline.example_log import example_log_path


@pytest.fixture(scope="module")
def example_signals():
    return read_log(example_log_path())


def test_core_methods_registered_in_order():
    names = list(methods())
    assert names[:4] == ["kf", "projection-mp", "projection-ls", "mhe"]
    assert len(set(names)) == len(names)


def test_unknown_name_lists_the_known_ones():
    with pytest.raises(UnknownMethodError) as error:
        method("kalman")
    message = str(error.value)
    assert "\n" not in message
    for name in methods():
        assert name in message


def test_lookup_is_case_insensitive_when_unambiguous():
    assert method("KF") is method("kf")


def test_method_info_rejects_bad_names():
    with pytest.raises(ValueError):
        MethodInfo(name="a b", description="", reference="", build=TwoStageKF)


def test_method_info_takes_only_a_frozen_options_dataclass():
    import dataclasses

    @dataclasses.dataclass
    class Mutable:
        horizon: int = 3

    for options in (dict, Mutable, Mutable()):
        with pytest.raises(TypeError, match="options must be a frozen dataclass"):
            MethodInfo(name="x", description="", reference="", build=TwoStageKF, options=options)


def test_family_modules_export_method_info():
    # Every family module present in this build contributes its entries (one, or a tuple of
    # variants: quasi_static's C and C-paper).
    import importlib
    import importlib.util

    present = [
        m for m in FAMILY_MODULES if importlib.util.find_spec(f"wheelload.estimators.family.{m}")
    ]
    entries = 0
    for module in present:
        info = importlib.import_module(f"wheelload.estimators.family.{module}").INFO
        entries += len(info) if isinstance(info, tuple) else 1
    assert len(present) == len(FAMILY_MODULES) and entries == len(present) + 1
    assert len(methods()) == 4 + entries


@pytest.mark.parametrize("name", ["kf", "projection-mp", "projection-ls", "mhe"])
def test_core_filters_meet_the_protocol(name, vehicle, example_signals):
    estimator = build(name, vehicle)
    assert isinstance(estimator, Estimator)
    signals = example_signals.slice(0, 50)
    by_steps = step_through(estimator, signals)
    whole = estimator.run(signals)
    # Same CasADi Functions (and, for the MHE, the same QP sequence at the log's 0.01 s
    # interval): rounding only, far below a newton.
    np.testing.assert_allclose(whole.loads, by_steps.loads, rtol=0, atol=1e-8)
    np.testing.assert_array_equal(whole.flags, by_steps.flags)


def test_options_reach_the_constructor(vehicle, example_signals):
    """``build(name, vehicle, **options)`` equals the constructor called with them."""
    from wheelload.estimators import GUARDS_OFF

    static = np.array([4000.0, 4100.0, 3500.0, 3550.0])
    built = build("kf", vehicle, static=static, guard_settings=GUARDS_OFF).run(example_signals)
    direct = TwoStageKF(vehicle, static=static, guard_settings=GUARDS_OFF).run(example_signals)
    np.testing.assert_array_equal(built.loads, direct.loads)
    np.testing.assert_array_equal(built.flags, direct.flags)


@pytest.mark.parametrize("name", ["kf", "projection-mp", "C"])
def test_an_option_the_method_does_not_take_is_named(name, vehicle):
    with pytest.raises(UnknownOptionError, match=f"method '{name}' takes no option 'horizon'"):
        build(name, vehicle, horizon=3)


def test_an_unknown_option_names_the_valid_ones(vehicle):
    with pytest.raises(UnknownOptionError) as error:
        build("B", vehicle, cutoff=2.0)
    message = str(error.value)
    assert "\n" not in message
    assert message == "method 'B' takes no option 'cutoff'; valid options: attitude_cutoff"


@pytest.mark.parametrize(
    ("name", "options", "expected"),
    [
        ("kf", {"guard_settings": "off"}, "option 'guard_settings' must be GuardSettings or None"),
        ("E", {"bandwidth": "25"}, "option 'bandwidth' must be float, got str"),
        ("mhe", {"interval": True}, "option 'interval' must be float, got bool"),
        ("tyre-forces", {"lateral": 1}, "option 'lateral' must be bool, got int"),
    ],
)
def test_an_option_of_the_wrong_type_is_named(name, options, expected, vehicle):
    with pytest.raises(UnknownOptionError, match=f"method '{name}': {expected}") as error:
        build(name, vehicle, **options)
    assert "valid options: " in str(error.value) and "\n" not in str(error.value)


def _constructor_options(info) -> dict:
    """The keyword parameters (with their defaults) the method's constructor takes beside
    the vehicle, its model and a projection's fixed weighting."""
    import inspect

    from wheelload.estimators.kf.projection import ProjectionKF

    constructor = {"kf": TwoStageKF, "projection-mp": ProjectionKF, "projection-ls": ProjectionKF}
    target = constructor.get(info.name, info.build)
    parameters = inspect.signature(target).parameters.values()
    return {
        p.name: p.default
        for p in parameters
        if p.name not in ("self", "vehicle", "suspension", "weighting")
    }


@pytest.mark.parametrize("name", [*methods(), *tyre_methods()])
def test_options_dataclass_declares_the_constructors_keywords(name):
    """Each method's frozen options dataclass: one field a constructor keyword, same default."""
    import dataclasses

    info = method(name)
    assert info.options.__dataclass_params__.frozen
    declared = {f.name: f.default for f in dataclasses.fields(info.options)}
    assert declared == _constructor_options(info)
