"""``wheelload_kf_set_param`` makes ``wheelload_kf_init``'s checks: a sweep and Hypothesis.

A sweep sets every field to each hostile value alone (0, ±1, negative, huge, NaN, ±inf,
denormals), and Hypothesis picks one to three calls of ``set_param`` (any field, those
values or the default scaled, so that accepted calls are drawn too); a driver program
built with the real compiler applies them, runs ``init`` and steps the compiled library
over 3 s of the bundled log (a real log, 100 Hz). Whatever the calls:

- the struct ``set_param`` leaves always passes ``init`` (one declaration of the checks);
- a refused call changes nothing: the run equals, to the bit (hex-float text), the run with
  only the accepted calls;
- no step is rejected (every accepted calibration keeps the step's arithmetic finite), the
  loads keep moving (never frozen), unless each held step says why: INTERVAL_SHORT (a
  nominal interval set above the log's: refused by design) or LOAD_LIMITED (a calibration
  the log contradicts, e.g. a mass whose load limit the logged loads exceed);
- no load leaves +-load_limit m g (m the larger of the mass in force and the online mass).
"""

import math

import numpy as np
import pytest
from c_parity import compile_program, kf_library, needs_gcc, run_program
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from wheelload.estimators import read_log
from wheelload.estimators.codegen.kf import CodegenOptions
from wheelload.estimators.codegen.runtime_parameters import PARAMETERS, SetStatus, runtime_fields
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.result import StepFlag
from wheelload.models import GRAVITY, ModelParameters, example_vehicle_path, load_vehicle
from wheelload.studies.pipeline.example_log import example_log_path

pytestmark = needs_gcc

SAMPLES = 300  # 3 s of the bundled log

DRIVER = r"""
#include "wheelload_kf.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* driver ROWS.txt [INDEX VALUE]...: set each, init, step over the rows (dt then the inputs,
 * one row a line, "nan" for a missing one); print statuses, init, then per step the loads,
 * the online mass and the flags as hex floats. */
int main(int argc, char **argv)
{
    wheelload_kf_params params = wheelload_kf_default_params;
    wheelload_kf_state state;
    wheelload_kf_output out;
    wheelload_kf_input input;
    static char line[65536];
    FILE *rows = fopen(argv[1], "r");
    int k;
    if (rows == NULL) {
        return 3;
    }
    for (k = 2; k + 1 < argc; k += 2) {
        const int status = wheelload_kf_set_param(&params, atoi(argv[k]), strtod(argv[k + 1], 0));
        printf("set %d\n", status);
    }
    printf("init %d\n", wheelload_kf_init(&state, &params));
    printf("limit %a %a\n", params.load_limit, params.mass);
    while (fgets(line, sizeof line, rows) != NULL) {
        char *cursor = line;
        const double dt = strtod(cursor, &cursor);
        for (k = 0; k < WHEELLOAD_KF_N_INPUTS; ++k) {
            *wheelload_kf_input_field(&input, k) = strtod(cursor, &cursor);
        }
        wheelload_kf_step(&state, &params, &input, dt, &out);
        printf("%a %a %a %a %a %u\n", out.loads[0], out.loads[1], out.loads[2], out.loads[3],
               out.mass_properties[0], (unsigned)out.flags);
    }
    fclose(rows);
    return 0;
}
"""


@pytest.fixture(scope="module")
def driver(tmp_path_factory):
    """The driver above linked with the bundled vehicle's library (double, runtime
    parameters, strict flags), and the rows of the log it steps over."""
    folder = tmp_path_factory.mktemp("set_param")
    library = kf_library(example_vehicle_path(), folder, CodegenOptions())
    source = folder / "driver.c"
    source.write_text(DRIVER)
    binary = compile_program(library, source, "driver")
    signals = read_log(example_log_path()).slice(0, SAMPLES)
    inputs = input_matrix(signals).T
    dt = sample_intervals(signals.t)
    rows = folder / "rows.txt"
    rows.write_text("".join(" ".join(map(repr, [float(d), *u])) + "\n" for d, u in zip(dt, inputs)))
    return binary, rows


def _defaults() -> dict[str, float]:
    from wheelload.estimators.kf.tuning import tuning_vector

    vehicle = load_vehicle(example_vehicle_path())
    values = [*ModelParameters.from_vehicle(vehicle).vector(), *tuning_vector(vehicle),
              vehicle.filter.initial_std]  # fmt: skip
    return dict(zip(runtime_fields(), values))


DEFAULTS = _defaults()
FIELDS = runtime_fields()
HOSTILE = (0.0, -0.0, 1.0, -1.0, -1e3, 1e308, -1e308, math.nan, math.inf, -math.inf,
           5e-324, -5e-324, 2.2250738585072014e-308, 1e15, 1e-6)  # fmt: skip


@st.composite
def calls(draw):
    """One to three ``(field index, value)``: a hostile value, or the default scaled."""
    chosen = []
    for _ in range(draw(st.integers(1, 3))):
        index = draw(st.integers(0, len(FIELDS) - 1))
        if draw(st.booleans()):
            value = draw(st.sampled_from(HOSTILE))
        else:
            factor = draw(st.sampled_from((0.0, -1.0, 0.5, 0.9, 1.1, 2.0, 10.0, 1e3, 1e6)))
            value = DEFAULTS[FIELDS[index]] * factor
        chosen.append((index, value))
    return chosen


def _run(driver, chosen):
    binary, rows = driver
    arguments = [text for index, value in chosen for text in (str(index), float.hex(value))]
    lines = run_program(binary, rows, *arguments).stdout.splitlines()
    statuses = [int(line.split()[1]) for line in lines[: len(chosen)]]
    init = int(lines[len(chosen)].split()[1])
    limit, mass = (float.fromhex(v) for v in lines[len(chosen) + 1].split()[1:])
    steps = lines[len(chosen) + 2 :]
    table = np.array([[float.fromhex(v) for v in line.split()[:5]] for line in steps])
    flags = np.array([int(line.split()[5]) for line in steps])
    return statuses, init, (limit, mass), steps, table, flags


def test_the_driver_sees_a_moving_filter_with_the_defaults(driver):
    """The run the properties compare against: loads move, no step rejected."""
    _, init, _, _, table, flags = _run(driver, [])
    assert init == 0 and len(table) == SAMPLES
    assert np.ptp(table[:, :4], axis=0).min() > 100.0  # N: the log's load transfer
    assert not (flags & int(StepFlag.STEP_REJECTED)).any()


def test_the_issue_s_refused_values_are_refused(driver):
    """mass -1, sample_interval 0, load_limit 0, zero process noise: accepted before (and
    sample_interval 0 froze the filter), refused now with SET_OUT_OF_RANGE."""
    for name, value in (("mass", -1.0), ("sample_interval", 0.0), ("load_limit", 0.0),
                        ("process_noise_density", 0.0)):  # fmt: skip
        statuses, init, *_ = _run(driver, [(FIELDS.index(name), value)])
        assert statuses == [int(SetStatus.OUT_OF_RANGE)], name
        assert init == 0


def _never_broken(limit, mass, table, flags):
    """No step rejected, loads moving (or held with a guard's bit), within the load limit."""
    # never a rejected step: every accepted calibration keeps the arithmetic finite
    assert not (flags & int(StepFlag.STEP_REJECTED)).any()
    assert np.isfinite(table).all()
    # never frozen: the loads move, unless each held step says why (refused for its interval,
    # or every update beyond the load limit: a calibration the log contradicts)
    held = np.all(np.diff(table[:, :4], axis=0) == 0.0, axis=1)
    said = (flags[1:] & int(StepFlag.INTERVAL_SHORT | StepFlag.LOAD_LIMITED)) != 0
    assert not held.all() or said.all()
    # never beyond the load limit
    weight = limit * np.maximum(mass, table[:, 4]) * GRAVITY
    assert (np.abs(table[:, :4]) <= weight[:, None] * (1 + 1e-12)).all()


def test_every_field_with_every_hostile_value(driver):
    """The sweep: each field set to each of the hostile values alone. Before: 149 of 889
    accepted values were ones init refuses, sample_interval 0 froze the filter. Now none
    accepted that init refuses, none breaks the filter."""
    accepted = 0
    for index, name in enumerate(FIELDS):
        for value in HOSTILE:
            statuses, init, (limit, mass), _, table, flags = _run(driver, [(index, value)])
            assert init == 0, (name, value)
            if statuses == [int(SetStatus.OK)]:
                accepted += 1
                assert PARAMETERS.domains()[name].holds(value), (name, value)
                _never_broken(limit, mass, table, flags)
    assert accepted > len(FIELDS)  # the sweep reaches the accepted branch


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow,
          HealthCheck.function_scoped_fixture])  # fmt: skip
@given(chosen=calls())
def test_set_param_never_breaks_the_filter(driver, chosen):
    statuses, init, (limit, mass), steps, table, flags = _run(driver, chosen)
    # the struct set_param leaves passes init's checks
    assert init == 0
    # values outside their domain are never accepted
    domains = PARAMETERS.domains()
    for (index, value), status in zip(chosen, statuses):
        if not domains[FIELDS[index]].holds(value):
            assert status != int(SetStatus.OK), (FIELDS[index], value)
    # a refused call leaves the outputs as if it had not been made (to the bit)
    accepted = [call for call, status in zip(chosen, statuses) if status == int(SetStatus.OK)]
    if len(accepted) < len(chosen):
        assert _run(driver, accepted)[3] == steps
    _never_broken(limit, mass, table, flags)
