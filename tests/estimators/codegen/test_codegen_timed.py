"""The generated C's time-stamped step (``wheelload_kf_step_at``) equals the Python timed filter.

A plant log sent as a CAN car sends it (tests/timed_logs.py: travel 100 Hz, IMU 200 Hz, speed
50 Hz, latencies 5-20 ms, clock jitter, frames out of order and far too late) runs through
the library (double, runtime parameters) under the strict flags, with a ring of 8 checkpoints
(``-DWHEELLOAD_KF_N_CHECKPOINTS=8``) so that both ways of dropping a measurement (beyond
max_rewind_age, before the oldest checkpoint of a full ring) occur, and through
:meth:`TwoStageKF.run_timed` with the same settings, and as a float build. Tolerance 1e-9 N
for the double build: the C runs the step Function's instructions in the same order as
Python's compiled step (symmetric storage of P aside), as the other parity tests
(tests/estimators/codegen/test_codegen.py); the float build's is stated at its test.

No allocation: the library's source names no allocator and its object file leaves none
undefined (``nm -u``): the ring is in the caller's struct.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from c_parity import compile_c, kf_library, needs_gcc, run_program

from wheelload.estimators.codegen.kf import STRICT_CFLAGS, CodegenOptions, Precision
from wheelload.estimators.kf.rewind import RewindSettings, measurements
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.result import StepFlag
from wheelload.models import INPUTS, example_vehicle_path

sys.path.insert(0, str(Path(__file__).parents[2]))
from timed_logs import can_car_log, latencies  # noqa: E402

pytestmark = needs_gcc

RING = 8
SETTINGS = RewindSettings(checkpoints=RING, max_rewind_age=0.5, speed_hold=1.0)
INTERVAL = 0.005

DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include "wheelload_kf.h"

/* argv[1]: lines "t,channels,u0,...,u(N-1)"; prints per line the loads, flags, newest t. */
int main(int argc, char **argv)
{
    static wheelload_kf_timed timed;
    wheelload_kf_params params = wheelload_kf_default_params;
    wheelload_kf_output out;
    char line[4096];
    FILE *in;
    int k;
    if (argc != 2 || (in = fopen(argv[1], "r")) == NULL) {
        return 2;
    }
    if (wheelload_kf_timed_init(&timed, &params, WHEELLOAD_KF_REAL_C(%(interval)r),
                                WHEELLOAD_KF_REAL_C(%(age)r), WHEELLOAD_KF_REAL_C(%(hold)r)) != 0) {
        return 3;
    }
    while (fgets(line, sizeof line, in) != NULL) {
        wheelload_kf_input input;
        char *cursor = line;
        wheelload_kf_real t = (wheelload_kf_real)strtod(cursor, &cursor);
        unsigned long channels = strtoul(cursor + 1, &cursor, 10);
        for (k = 0; k < WHEELLOAD_KF_N_INPUTS; ++k) {
            *wheelload_kf_input_field(&input, k) = (wheelload_kf_real)strtod(cursor + 1, &cursor);
        }
        wheelload_kf_step_at(&timed, &params, &input, (uint32_t)channels, t, &out);
        printf("%%.17g,%%.17g,%%.17g,%%.17g,%%lu,%%.17g\n", (double)out.loads[0],
               (double)out.loads[1], (double)out.loads[2], (double)out.loads[3],
               (unsigned long)out.flags, (double)timed.t);
    }
    fclose(in);
    printf("counts,%%lu,%%lu,%%lu\n", (unsigned long)timed.dropped,
           (unsigned long)timed.rewinds, (unsigned long)timed.replayed);
    return 0;
}
"""


def _timed_program(folder: Path, precision: Precision):
    """The library's object (ring of 8, strict flags) and the driver linked with it."""
    options = CodegenOptions(sample_interval=INTERVAL, precision=precision)
    library = kf_library(example_vehicle_path(), folder, options)
    flags = (*STRICT_CFLAGS, f"-DWHEELLOAD_KF_N_CHECKPOINTS={RING}")
    obj = compile_c(folder / "wheelload_kf.o", [library.source], (*flags, "-c"), libraries=())
    driver = folder / "timed_driver.c"
    values = {"interval": INTERVAL, "age": SETTINGS.max_rewind_age, "hold": SETTINGS.speed_hold}
    driver.write_text(DRIVER % values)
    binary = compile_c(folder / "timed", [driver, obj], flags, includes=(f"-I{folder}",))
    return library, obj, binary


@pytest.fixture(scope="module")
def timed_program(tmp_path_factory):
    """The double build's object and driver."""
    return _timed_program(tmp_path_factory.mktemp("timed_c"), Precision.DOUBLE)


@pytest.fixture(scope="module")
def can_measurements(plant_log):
    t, inputs = can_car_log(plant_log("iso-dlc"), 5.0)
    return measurements(t, inputs, latencies())


def _run_c(binary: Path, stamps, channels, folder: Path):
    """The C driver on the measurements: ``(rows of loads, flags, newest t; counts)``."""
    present = np.isfinite(channels)
    masks = (present * (1 << np.arange(len(INPUTS)))).sum(axis=1)
    lines = [
        ",".join([repr(float(t)), str(int(mask)), *(repr(float(v)) for v in row)])
        for t, mask, row in zip(stamps, masks, channels, strict=True)
    ]
    log = folder / "measurements.csv"
    log.write_text("\n".join(lines) + "\n")
    printed = run_program(binary, log).stdout.strip().splitlines()
    counts = [int(v) for v in printed[-1].split(",")[1:]]
    return np.array([[float(v) for v in line.split(",")] for line in printed[:-1]]), counts


@pytest.fixture(scope="module")
def python_run(vehicle, can_measurements):
    stamps, channels = can_measurements
    kf = TwoStageKF(vehicle, sample_interval=INTERVAL, check_file=False)
    return kf.run_timed(stamps, channels, settings=SETTINGS)  # latencies already applied


def test_the_c_timed_step_equals_python_on_a_can_car_log(timed_program, can_measurements,
                                                         python_run, tmp_path):  # fmt: skip
    _, _, binary = timed_program
    c, counts = _run_c(binary, *can_measurements, tmp_path)
    python = python_run
    too_old = int(StepFlag.MEASUREMENT_TOO_OLD)
    assert python.rewinds > 300 and python.dropped > 3, "rewinds and both kinds of drop"
    assert counts == [python.dropped, python.rewinds, python.replayed]
    np.testing.assert_allclose(c[:, :4], python.arrival_loads, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(c[:, 4].astype(np.int64), python.arrival_flags)
    np.testing.assert_array_equal(c[:, 5], python.arrival_time)
    assert np.sum(c[:, 4] == too_old) == python.dropped


def test_the_float_build_of_the_timed_step_follows_python(tmp_path, can_measurements,
                                                          python_run):  # fmt: skip
    """The float build (time stamps and state in float) on the same log: the loads within
    0.5 N of Python's doubles (as the float build of the step, test_codegen.py: float's
    2^-24 on loads of ~4 kN and on the P updates that weigh them), the same measurements
    dropped and rewound, the flags equal but for a bit or two of a few guards at a
    threshold."""
    _, _, binary = _timed_program(tmp_path, Precision.FLOAT)
    c, counts = _run_c(binary, *can_measurements, tmp_path)
    python = python_run
    assert counts[:2] == [python.dropped, python.rewinds]
    assert np.max(np.abs(c[:, :4] - python.arrival_loads)) < 0.5
    differ = c[:, 4].astype(np.int64) != python.arrival_flags
    assert np.mean(differ) < 0.01
    np.testing.assert_allclose(c[:, 5], python.arrival_time, rtol=0, atol=1e-6)


def test_the_timed_step_allocates_nothing(timed_program):
    library, obj, _ = timed_program
    source = library.source.read_text()
    assert "wheelload_kf_step_at" in source
    for allocator in ("malloc", "calloc", "realloc", "free(", "alloca"):
        assert allocator not in source, allocator
    undefined = subprocess.run(["nm", "-u", str(obj)], check=True, capture_output=True,
                               text=True).stdout.split()  # fmt: skip
    assert "wheelload_kf_step_at" not in undefined
    assert not {"malloc", "calloc", "realloc", "free"} & set(undefined), undefined
