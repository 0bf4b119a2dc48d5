"""The tyre-force step as C (``codegen --tyre-forces``): the generated example against the
Python ``tyre-forces`` method on a plant lane change (real gcc, strict flags, CSV files).

One iso-dlc simulation (1353 samples), one library per precision; about 20 s in all.
"""

import dataclasses

import numpy as np
import pytest
from c_parity import assert_c_equals_python, kf_program, lane_change_logs, run_program

from wheelload.estimators import read_log
from wheelload.estimators.codegen.kf import CodegenOptions
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.registry import build
from wheelload.estimators.result import StepFlag
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.models.vehicle.wheel_geometry import wheel_centres

WHEELS = ("fl", "fr", "rl", "rr")
#: Cells made missing in the log with gaps: (column, first row, last row).
GAPS = (("omega_fr", 300, 310), ("torque_rl", 500, 500), ("steer", 600, 605), ("wz", 700, 720),
        ("ax", 800, 800), ("vx", 900, 903))  # fmt: skip


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """The plant's lane change as CSV, clean and with the :data:`GAPS`."""
    logs = lane_change_logs(tmp_path_factory.mktemp("tyre_logs"), GAPS)
    return {name: path for name, (path, _) in logs.items()}


def _example(tmp_path_factory, precision):
    out = tmp_path_factory.mktemp(f"tyre_{precision.value}")
    options = CodegenOptions(precision=precision, tyre_forces=True)
    return kf_program(example_vehicle_path(), out, options)


def _run(binary, log):
    out = log.with_name(f"{log.stem}.{binary.parent.name}.out.csv")
    result = run_program(binary, log, out, check=False)
    assert result.returncode == 0, result.stderr
    import pandas as pd

    return pd.read_csv(out)


def _python(log):
    return build("tyre-forces", load_vehicle(example_vehicle_path())).run(read_log(log))


def _columns(frame, name):
    return frame[[f"{name}_{wheel}" for wheel in WHEELS]].to_numpy()


@pytest.mark.parametrize("which", ["clean", "gaps"])
def test_c_equals_python_in_double(tmp_path_factory, logs, which):
    """Double build: F_x, F_y, their σ and F_z equal the Python method's to 1e-9 N
    (measured 1.4e-12 N on the clean log), gaps included; where a spin is missing F_x holds
    its last value with the large σ, in both."""
    binary = _example(tmp_path_factory, Precision.DOUBLE)
    c, python = _run(binary, logs[which]), _python(logs[which])
    for name, values in (("fz", python.loads), ("fx", python.fx), ("fx_std", python.fx_std),
                         ("fy", python.fy), ("fy_std", python.fy_std)):  # fmt: skip
        assert_c_equals_python(_columns(c, name), values, rtol=0, atol=1e-9, what=name)
    slipping = (python.flags & StepFlag.HIGH_SLIP) != 0
    np.testing.assert_array_equal(c["high_slip"].to_numpy() == 1, slipping)
    if which == "gaps":
        held = _columns(c, "fx")[300:311]
        np.testing.assert_array_equal(held, np.repeat(held[:1], 11, axis=0))
        assert np.all(_columns(c, "fx_std")[300:311] >= 1e4)
        assert np.all(np.isfinite(_columns(c, "fy")))


def test_c_in_float_stays_near_double(tmp_path_factory, logs):
    """Float build on the clean log: F_x and F_y within 0.05 N of Python's double (single
    precision rounds near 1e-7 relative on forces of up to ~6 kN; measured 4.2e-3 N)."""
    binary = _example(tmp_path_factory, Precision.FLOAT)
    c, python = _run(binary, logs["clean"]), _python(logs["clean"])
    for name, values in (("fx", python.fx), ("fy", python.fy)):
        assert np.max(np.abs(_columns(c, name) - values)) < 0.05, name


def test_example_names_a_missing_wheel_channel(tmp_path_factory, logs):
    """A log without a wheel channel: exit status 2 and a message naming the column."""
    binary = _example(tmp_path_factory, Precision.DOUBLE)
    text = logs["clean"].read_text().splitlines()
    names = text[0].split(",")
    keep = [k for k, name in enumerate(names) if name != "torque_rr"]
    bare = logs["clean"].with_name("bare.csv")
    bare.write_text("".join(",".join(row.split(",")[k] for k in keep) + "\n" for row in text))
    result = run_program(binary, bare, "-", check=False)
    assert result.returncode == 2
    assert "missing column 'torque_rr'" in result.stderr


def test_the_tyre_numbers_set_at_run_time_equal_python_with_those_numbers(tmp_path_factory, logs):
    """``tyre.NAME=VALUE`` (``wheelload_kf_tyre_set_param``): a yaw inertia and a wheelbase
    split set at run time give the Python method whose constants have them (the wheel
    centres following lf), to 1e-9 N; the changed numbers move F_y by more than 1 N."""
    binary = _example(tmp_path_factory, Precision.DOUBLE)
    out = logs["clean"].with_name("set.csv")
    result = run_program(binary, logs["clean"], out, "tyre.yaw_inertia=3000", "tyre.lf=1.3",
                         check=False)  # fmt: skip
    assert result.returncode == 0, result.stderr
    import pandas as pd

    c = pd.read_csv(out)
    vehicle = load_vehicle(example_vehicle_path())
    method = build("tyre-forces", vehicle)
    k = method.constants
    geometry = dataclasses.replace(vehicle.geometry, lf=1.3)
    method.constants = dataclasses.replace(k, yaw_inertia=3000.0, lf=1.3,
                                           positions=wheel_centres(geometry))  # fmt: skip
    python = method.run(read_log(logs["clean"]))
    for name, values in (("fx", python.fx), ("fy", python.fy)):
        assert_c_equals_python(_columns(c, name), values, rtol=0, atol=1e-9, what=name)
    assert np.abs(_columns(c, "fy") - _python(logs["clean"]).fy).max() > 1.0


@pytest.mark.parametrize(
    ("assignment", "reason"),
    [("tyre.radius_fl=0.3", "fixed by the observers' discretisation"),
     ("tyre.rolling=-1", "outside its range"), ("tyre.yaw_inertia=0", "outside its range")],
)  # fmt: skip
def test_a_refused_tyre_number_is_named(tmp_path_factory, logs, assignment, reason):
    """A spin radius (it sets the discretisation) or a value outside its domain: refused,
    exit status 2, the assignment and the reason named, no estimates written."""
    binary = _example(tmp_path_factory, Precision.DOUBLE)
    out = logs["clean"].with_name("refused.csv")
    result = run_program(binary, logs["clean"], out, assignment, check=False)
    assert result.returncode == 2
    assert assignment in result.stderr and reason in result.stderr
    assert not out.exists()
