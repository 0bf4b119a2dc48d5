"""Run-time parameters of the generated KF C: a set source moves its derived parameters.

The derived parameters (the static loads from the mass and CG, the roll split from the
springs, bars and links) are recomputed by ``wheelload_kf_set_param`` with C emitted
from the CasADi Function the Python parameters take them from
(``wheelload.models.parameters.derived_function``). Built with the strict flags (no FMA
contraction), the double C executes that Function's instructions in its order, so a
derived value equals Python's to the bit. The loads then equal the Python filter built
from the changed vehicle file to 1e-9 N: the C step's instruction order differs from the
Python step's (symmetric storage, common subexpressions), a rounding difference measured
at 2.7e-12 N over the bundled log (1353 samples of loads up to 6 kN), far below the 2.2 N
a stale roll split gave.
"""

import dataclasses

import numpy as np
import pandas as pd
import pytest
from c_parity import assert_c_equals_python, compile_program, kf_library, run_program

from wheelload.estimators import read_log
from wheelload.estimators.codegen.kf import CodegenOptions
from wheelload.estimators.codegen.runtime_parameters import SetStatus, runtime_fields
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.result import WHEELS
from wheelload.models import ModelParameters, example_vehicle_path
from wheelload.models.parameters import derived_function
from wheelload.studies.pipeline.example_log import example_log_path

LOADS = [f"fz_{w}" for w in WHEELS]
#: C and Python loads (module docstring): the steps' rounding, 2.7e-12 N measured.
TOLERANCE = 1e-9  # N


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    """The bundled vehicle's library (double, runtime parameters)."""
    return kf_library(example_vehicle_path(), tmp_path_factory.mktemp("c"), CodegenOptions())


@pytest.fixture(scope="module")
def example(library):
    return compile_program(library, library.example, "example")


@pytest.fixture(scope="module")
def log():
    return read_log(example_log_path())


def run_example(example, out, *overrides):
    return run_program(example, example_log_path(), out, *overrides, check=False)


def changed_vehicle(vehicle, *, spring_front=None, roll_split_front=None):
    suspension = vehicle.suspension
    if spring_front is not None:
        front = dataclasses.replace(suspension.front, spring_rate=spring_front)
        suspension = dataclasses.replace(suspension, front=front)
    if roll_split_front is not None:
        suspension = dataclasses.replace(suspension, roll_split_front=roll_split_front)
    return vehicle.replace(suspension=suspension)


def test_a_spring_set_at_run_time_equals_the_python_filter_of_the_changed_file(
    vehicle, example, log, tmp_path
):
    out = tmp_path / "spring.csv"
    assert run_example(example, out, "spring_front=66000").returncode == 0
    c = pd.read_csv(out)[LOADS].to_numpy()
    changed = changed_vehicle(vehicle, spring_front=66000.0)
    python = TwoStageKF(changed).run(log).loads
    assert_c_equals_python(c, python, rtol=0, atol=TOLERANCE)
    # The split the file's springs gave, left stale, is off by newtons.
    split = ModelParameters.from_vehicle(vehicle).roll_split_front
    stale = changed_vehicle(vehicle, spring_front=66000.0, roll_split_front=split)
    assert np.abs(TwoStageKF(stale).run(log).loads - python).max() > 1.0


@pytest.mark.parametrize("order", [1, -1])
def test_a_split_set_at_run_time_is_pinned_whatever_the_order(
    vehicle, example, log, tmp_path, order
):
    out = tmp_path / "pinned.csv"
    overrides = ["roll_split_front=0.45", "spring_front=66000"][::order]
    assert run_example(example, out, *overrides).returncode == 0
    changed = changed_vehicle(vehicle, spring_front=66000.0, roll_split_front=0.45)
    python = TwoStageKF(changed).run(log).loads
    assert_c_equals_python(pd.read_csv(out)[LOADS], python, rtol=0, atol=TOLERANCE)


def test_a_mass_centre_input_is_refused_with_the_fix(example, tmp_path):
    out = tmp_path / "refused.csv"
    result = run_example(example, out, "sprung_mass=1500")
    assert result.returncode == 2
    assert result.stderr.splitlines() == [
        "sprung_mass=1500: 'sprung_mass' moves the mass centre with vehicle-file values this "
        "library does not hold: regenerate the library from the changed vehicle file"
    ]
    assert not out.exists()
    result = run_example(example, out, "spring_frnt=66000")
    assert result.returncode == 2 and "spring_frnt=66000: unknown parameter" in result.stderr


DRIVER = r"""
#include "wheelload_kf.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static int field(const char *name)
{
    int k;
    for (k = 0; k < WHEELLOAD_KF_N_PARAMS; ++k) {
        if (strcmp(wheelload_kf_param_names[k], name) == 0) {
            return k;
        }
    }
    return -1;
}

int main(void)
{
    wheelload_kf_params params = wheelload_kf_default_params;
    wheelload_kf_state state;
    const int spring = field("spring_front"), mass = field("mass");
    const int split = field("roll_split_front"), sprung = field("sprung_mass");
    int status, other;
    /* each status is taken before the fields are printed (argument order is unspecified) */
    status = wheelload_kf_set_param(&params, -1, 1.0);
    other = wheelload_kf_set_param(&params, WHEELLOAD_KF_N_PARAMS, 1.0);
    printf("unknown %d %d\n", status, other);
    status = wheelload_kf_set_param(&params, spring, NAN);
    other = wheelload_kf_set_param(&params, spring, INFINITY);
    printf("not_finite %d %d\n", status, other);
    status = wheelload_kf_set_param(&params, sprung, 1500.0);
    other = wheelload_kf_set_param(&params, sprung, params.sprung_mass); /* its own value */
    printf("fixed %d %d %.17g\n", status, other, params.sprung_mass);
    printf("refused_left %.17g %.17g\n", params.spring_front, params.roll_split_front);
    status = wheelload_kf_set_param(&params, spring, 66000.0);
    printf("spring %d %.17g\n", status, params.roll_split_front);
    status = wheelload_kf_set_param(&params, mass, 1700.0);
    printf("mass %d %.17g %.17g %.17g %.17g %.17g\n", status, params.static_fl,
           params.static_fr, params.static_rl, params.static_rr, params.roll_split_front);
    printf("init %d\n", wheelload_kf_init(&state, &params));
    printf("reset_loads %.17g %.17g\n", state.x[0], state.x[2]);
    params.spring_rear = 71000.0; /* written directly: the split would be stale */
    printf("direct %d\n", wheelload_kf_init(&state, &params));
    params = wheelload_kf_default_params;
    params.roll_split_front = 0.4; /* a derived parameter written directly */
    printf("direct_derived %d\n", wheelload_kf_init(&state, &params));
    params = wheelload_kf_default_params;
    status = wheelload_kf_set_param(&params, split, 0.45);
    other = wheelload_kf_set_param(&params, spring, 66000.0);
    printf("pin %d %d %.17g\n", status, other, params.roll_split_front);
    printf("pinned_init %d\n", wheelload_kf_init(&state, &params));
    return 0;
}
"""


def test_set_param_statuses_and_derived_values_equal_python_to_the_bit(vehicle, library):
    driver = library.header.parent / "set_param_driver.c"
    driver.write_text(DRIVER)
    binary = compile_program(library, driver, "set_param_driver")
    lines = run_program(binary).stdout
    report = {line.split()[0]: line.split()[1:] for line in lines.splitlines()}
    fields = runtime_fields()
    default = ModelParameters.from_vehicle(vehicle)
    assert report["unknown"] == [str(int(SetStatus.UNKNOWN))] * 2
    assert report["not_finite"] == [str(int(SetStatus.NOT_FINITE))] * 2
    assert report["fixed"] == [str(int(SetStatus.FIXED)), "0", repr(default.sprung_mass)]
    # a refused value leaves the struct as it was
    assert [float(v) for v in report["refused_left"]] == [default.spring_front,
                                                          default.roll_split_front]  # fmt: skip
    # the split of the changed file (from_vehicle: the same Function), to the bit
    changed = ModelParameters.from_vehicle(changed_vehicle(vehicle, spring_front=66000.0))
    assert report["spring"] == ["0", repr(changed.roll_split_front)]
    # mass then moves the static loads and the split (ModelParameters with both set)
    heavier = dataclasses.replace(changed, mass=1700.0)
    expected = derived_function()(heavier.vector()).full().ravel()
    assert report["mass"][0] == "0"
    assert [float(v) for v in report["mass"][1:]] == list(expected)
    assert expected[0] > default.static_fl + 200.0  # 87 kg more: 233 N on a front wheel
    assert report["init"] == ["0"]
    # reset starts from the recomputed static loads
    assert [float(v) for v in report["reset_loads"]] == [expected[0], expected[2]]
    # a source or a following derived parameter written directly: -(1 + its index)
    assert report["direct"] == [str(-(1 + fields.index("spring_rear")))]
    assert report["direct_derived"] == [str(-(1 + fields.index("roll_split_front")))]
    # set first, the split stays the value given when a spring is set after it
    assert report["pin"] == ["0", "0", "0.45000000000000001"]
    assert report["pinned_init"] == ["0"]
