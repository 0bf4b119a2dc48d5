"""The embedded MHE C is re-entrant: instances in one program are independent estimators.

All that one instance keeps between samples, its OSQP solver and its fallback filter
included, is one caller-owned ``wheelload_mhe_state``. The generated example program, built
by the real gcc, runs one instance per log, interleaved sample by sample; each log's output
is then the same file, byte for byte, as that of the program run on that log alone (no
state is shared: the same instructions on the same data), and equals the Python MHE to the
tolerance of the other MHE C tests (tests/estimators/codegen/test_mhe_codegen.py and
test_mhe_codegen_settings.py).
"""

import dataclasses
import os
import shutil
import subprocess

import numpy as np
import pandas as pd
import pytest
from c_parity import (
    assert_c_equals_python,
    compile_c,
    mhe_library,
    mhe_program,
    needs_gcc,
    run_program,
)

from wheelload.estimators import read_log
from wheelload.estimators.codegen.mhe import embedded_settings, generate_mhe
from wheelload.estimators.codegen.mhe_build import write_inputs
from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
from wheelload.estimators.mhe.settings import (
    BiasStates,
    Loss,
    MheSettings,
    ResidualLoss,
    SolverSettings,
)
from wheelload.models import example_vehicle_path
from wheelload.studies.drive.synthetic import SensorNoise, steady_cornering, synthetic_log
from wheelload.studies.pipeline.example_log import example_log_path

pytestmark = needs_gcc

LOADS = ["fz_fl", "fz_fr", "fz_rl", "fz_rr"]
#: Both sides solve to 1e-9 kN: they agree far below a newton whatever the ADMM path.
TIGHT = SolverSettings(eps_abs=1e-9, eps_rel=1e-9, max_iter=20000)
#: (settings, load tolerance [N]) per window driver, each with the KF linked in. Quadratic
#: window at OSQP's defaults: the same ADMM iterations in C and Python, a tenth of the
#: 1e-6 kN tolerance scaled to newtons; robust window with bias states at 1e-9: 0.01 N.
DRIVERS = {
    "plain-soft-bounded": (MheSettings(horizon=10, bounded=True), 0.1),
    "window-huber-bias-lag": (
        MheSettings(
            horizon=6,
            bounded=True,
            lag=2,
            solver=TIGHT,
            suspension_loss=ResidualLoss(kind=Loss.HUBER, threshold=2.0),
            bias_states=BiasStates.TRAVEL | BiasStates.ACCELERATION,
        ),
        0.01,
    ),  # fmt: skip
}


@pytest.fixture(scope="module")
def logs(vehicle):
    """Two different logs of different lengths: a slice of the bundled plant log with a
    travel offset, and a synthetic corner that lifts a wheel."""
    plant = read_log(example_log_path()).slice(300, 600)
    d = plant.d.copy()
    d[:, 2] += 0.004  # a ride-height offset for the bias states
    noise = SensorNoise(acceleration=0.05, travel=0.0003)
    corner = synthetic_log(vehicle, steady_cornering(ay=15.0, duration=2.0), noise=noise, seed=7)
    return {"plant": dataclasses.replace(plant, d=d), "corner": corner.slice(0, 180)}


def run(binary, *pairs):
    run_program(binary, *pairs)


@pytest.mark.parametrize("driver", list(DRIVERS))
def test_two_interleaved_instances_each_equal_one_alone_and_python(vehicle, logs, tmp_path, driver):
    settings, tolerance = DRIVERS[driver]
    binary = mhe_program(vehicle, settings, tmp_path / "c", 0.01,
                         vehicle_path=example_vehicle_path())  # fmt: skip
    inputs = {name: write_inputs(log, tmp_path / f"{name}.txt") for name, log in logs.items()}
    run(binary, inputs["plant"], tmp_path / "plant_pair.csv",
        inputs["corner"], tmp_path / "corner_pair.csv")  # fmt: skip
    realised = embedded_settings(settings, filter_linked=True)
    lag = settings.lag
    for name, log in logs.items():
        alone = tmp_path / f"{name}_alone.csv"
        run(binary, inputs[name], alone)
        pair = (tmp_path / f"{name}_pair.csv").read_bytes()
        assert pair == alone.read_bytes(), name  # the other instance changed nothing
        c = pd.read_csv(alone)
        assert len(c) == len(log) and (c["status"] == 1).all() and not c["fallback"].any()
        python = MovingHorizonEstimator(vehicle, realised).run(log)
        n = len(log) - lag  # row k of the C is the estimate of sample k - lag
        assert_c_equals_python(c[LOADS].to_numpy()[lag:], python.loads[:n], rtol=0,
                               atol=tolerance, what=name)  # fmt: skip
        np.testing.assert_array_equal(c["flags"], python.flags, err_msg=name)
    # the two logs give different estimates: an instance that read the other's would show
    plant, corner = (pd.read_csv(tmp_path / f"{n}_pair.csv")[LOADS] for n in ("plant", "corner"))
    assert np.abs(plant.to_numpy()[:50] - corner.to_numpy()[:50]).max() > 100.0


def test_a_reset_sets_the_solver_up_afresh(vehicle, tmp_path):
    """A log run twice in one loaded library gives the same numbers to the bit: the reset
    restores the instance's whole solver (before, the file-scope solver kept its adapted
    state across logs: the second run of the bundled log was 2.6e-3 N off, soft N = 20)."""
    library = mhe_library(vehicle, MheSettings(horizon=20, bounded=True), tmp_path, 0.01,
                          vehicle_path=example_vehicle_path())  # fmt: skip
    log = read_log(example_log_path())
    first, second = library.run(log), library.run(log)
    np.testing.assert_array_equal(first.loads, second.loads)
    np.testing.assert_array_equal(first.iterations, second.iterations)
    assert library.state_size > 1000  # the window, the filter and the solver: bytes


MISUSE = r"""
#include <stdio.h>
#include <string.h>
#include "wheelload_mhe.h"

static wheelload_mhe_state never_reset; /* zeroed, never reset */

int main(void) {
    static wheelload_mhe_state first, copy;
    double u[WHEELLOAD_MHE_N_INPUTS];
    wheelload_mhe_output out;
    int k, status;
    for (k = 0; k < WHEELLOAD_MHE_N_INPUTS; ++k) u[k] = 0.0;
    u[10] = 9.81; /* az at rest: a valid sample */
    /* each status is taken before out is printed (argument order is unspecified) */
    status = wheelload_mhe_step(&never_reset, u, 0.01, &out);
    printf("never_reset %d %u\n", status, out.flags);
    wheelload_mhe_reset(&first);
    memcpy(&copy, &first, sizeof first); /* its solver still points into first */
    status = wheelload_mhe_step(&copy, u, 0.01, &out);
    printf("copy %d %u\n", status, out.flags);
    status = wheelload_mhe_step(&first, u, 0.01, &out);
    printf("first %d %.3f\n", status, out.loads[0]);
    wheelload_mhe_reset(&copy); /* reset where it is: an instance of its own */
    status = wheelload_mhe_step(&copy, u, 0.01, &out);
    printf("copy_reset %d %.3f\n", status, out.loads[0]);
    printf("size %d\n", wheelload_mhe_state_size() == sizeof(wheelload_mhe_state));
    return 0;
}
"""


def test_a_state_not_reset_where_it_is_is_refused(vehicle, tmp_path):
    """A program linked with the Makefile's library (its own code warning-free under -Wall)."""
    from wheelload.estimators.codegen.mhe import mhe_includes
    from wheelload.models.inputs import INPUTS

    assert INPUTS[10] == "az"
    folder = generate_mhe(vehicle, MheSettings(horizon=4), tmp_path / "c", 0.01)
    subprocess.run(["make", "-s", "-C", str(folder), "libwheelload_mhe.a"], check=True,
                   capture_output=True)  # fmt: skip
    (folder / "misuse.c").write_text(MISUSE)
    binary = compile_c(
        folder / "misuse",
        [folder / "misuse.c", folder / "libwheelload_mhe.a"],
        ("-O2", "-std=gnu99", "-Wall", "-Werror"),
        includes=mhe_includes(folder),
    )
    lines = run_program(binary).stdout
    report = {line.split()[0]: line.split()[1:] for line in lines.splitlines()}
    assert report["never_reset"] == ["-1", "255"]  # WHEELLOAD_MHE_NOT_RESET, nothing estimated
    assert report["copy"] == ["-1", "255"]
    assert report["first"][0] == "1" and report["copy_reset"] == report["first"]
    assert float(report["first"][1]) > 1000.0  # a static front load, estimated
    assert report["size"] == ["1"]


def make_commands(folder, *args, **extra):
    """``make -n`` in ``folder``: the commands it would run (CC only from ``extra``/``args``)."""
    environment = {k: v for k, v in os.environ.items() if k != "CC"}
    return subprocess.run(["make", "-n", "-C", str(folder), *args], check=True,
                          capture_output=True, text=True, env={**environment, **extra}
                          ).stdout  # fmt: skip


def test_the_mhe_makefile_takes_gcc_unless_cc_is_given_and_builds_the_example(
    vehicle, logs, tmp_path
):
    """As the KF's: make's built-in ``CC = cc`` does not count; ``CC=... make`` and ``make
    CC=...`` do. Built for real with ``CC=cc`` (and with clang where installed), the example
    gives the output of the program built by :func:`build_mhe_program`."""
    settings = MheSettings(horizon=5, bounded=True)
    folder = generate_mhe(vehicle, settings, tmp_path / "mhe", 0.01)
    compiles = [line for line in make_commands(folder).splitlines() if " -c " in line]
    assert compiles and all(line.startswith("gcc -O2 -std=gnu99") for line in compiles)
    assert "my-cc -O2" in make_commands(folder, CC="my-cc")
    assert "other-cc -O2" in make_commands(folder, "CC=other-cc")
    linked = [line for line in make_commands(folder).splitlines() if "-o wheelload_mhe " in line]
    assert linked and "libwheelload_mhe.a -lm" in linked[0]
    inputs = write_inputs(logs["corner"], tmp_path / "corner.txt")
    reference = mhe_program(vehicle, settings, tmp_path / "reference", 0.01)
    run(reference, inputs, tmp_path / "reference.csv")
    compilers = [("cc", {"CC": "cc"}, [])]
    if shutil.which("clang"):
        compilers.append(("clang", {}, ["CC=clang"]))
    for name, environment, args in compilers:
        subprocess.run(["make", "-s", "-C", str(folder), "clean"], check=True)
        subprocess.run(["make", "-s", "-C", str(folder), *args], check=True, capture_output=True,
                       env={**os.environ, **environment})  # fmt: skip
        out = tmp_path / f"{name}.csv"
        run(folder / "wheelload_mhe", inputs, out)
        # gcc (cc is gcc here) at the same flags: the same numbers, to the 9 digits printed
        built, expected = pd.read_csv(out)[LOADS], pd.read_csv(tmp_path / "reference.csv")[LOADS]
        np.testing.assert_allclose(built, expected, rtol=0, atol=0.0 if name == "cc" else 0.1)
