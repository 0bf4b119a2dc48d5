"""The source FMU (``codegen --fmu``) as an importer sees it: FMPy validates it, compiles its
sources with the real compiler (FMPy's CMake build, its FMI 3.0 headers) and simulates a plant
lane change through it; the outputs equal the Python ``tyre-forces`` method's.

One iso-dlc simulation (1353 samples at 100 Hz, with wheel spins, torques and steer), one FMU,
compiled once, by FMPy's Debug configuration (gcc -O0 -g: the equality does not depend on the
optimisation, and -O0 builds the library several times faster than the Release -O3).
"""

import dataclasses
import zipfile

import numpy as np
import pytest
from c_parity import (
    assert_c_equals_python,
    compile_c,
    lane_change_logs,
    needs_gcc,
)

from wheelload.estimators import read_log
from wheelload.estimators.codegen.fmu import generate_fmu
from wheelload.estimators.codegen.fmu_variables import FMU_INPUTS, OUTPUT_GROUPS
from wheelload.estimators.codegen.kf import STRICT_CFLAGS, CodegenOptions
from wheelload.estimators.codegen.runtime_parameters import PARAMETERS
from wheelload.estimators.family.tyres.step import WHEEL_INPUTS
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.registry import build
from wheelload.models import WHEELS, example_vehicle_path, load_vehicle
from wheelload.models.parameters import MASS_CENTRE_INPUTS

fmpy = pytest.importorskip("fmpy", reason="FMPy (the test extra: pip install -e '.[test]')")
from fmpy.build import build_platform_binary  # noqa: E402
from fmpy.fmi3 import FMU3Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

pytestmark = [needs_gcc, pytest.mark.heavy(40)]  # seconds (tests/conftest.py)

INTERVAL = 0.01  # s, the library's default sample interval: the plant log's
#: Cells made missing in the log with gaps (column, first row, last row): the status bits fire.
GAPS = (("omega_fr", 300, 310), ("torque_rl", 500, 500), ("steer", 600, 605), ("wz", 700, 720),
        ("ax", 800, 800), ("vx", 900, 903), ("d_fl", 1000, 1004))  # fmt: skip
OUTPUTS = [f"{group}_{wheel}" for group, _, _ in OUTPUT_GROUPS for wheel in WHEELS]


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """The plant's lane change as CSV, clean and with the :data:`GAPS`; and its frame."""
    return lane_change_logs(tmp_path_factory.mktemp("fmu_logs"), GAPS)


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    """The FMU of the example vehicle, and its folder extracted and compiled by FMPy."""
    out = tmp_path_factory.mktemp("fmu")
    generated = generate_fmu(example_vehicle_path(), out / "dist")
    unzipped = out / "unzipped"
    fmpy.extract(str(generated.path), str(unzipped))
    (out / "build").mkdir()
    build_platform_binary(unzipped, out / "build", configuration="Debug")
    return generated, unzipped


def _signals(frame):
    """The log's channels the FMU takes, as FMPy's input table (the time column first)."""
    names = [name for name in (*FMU_INPUTS, *WHEEL_INPUTS) if name in frame.columns]
    table = np.zeros(len(frame), dtype=[("time", float)] + [(name, float) for name in names])
    table["time"] = frame["t"].to_numpy()
    for name in names:
        table[name] = frame[name].to_numpy()
    return table


def _simulate(unzipped, frame, start_values=None):
    """FMPy's co-simulation of the log: row k of the result is the estimate of sample k (the
    outputs at t[k] + interval, after the step that held sample k's inputs)."""
    t = frame["t"].to_numpy()
    result = fmpy.simulate_fmu(
        str(unzipped), start_time=t[0], stop_time=t[-1] + INTERVAL, output_interval=INTERVAL,
        input=_signals(frame), output=[*OUTPUTS, "status", "faults"],
        start_values=start_values or {},
    )  # fmt: skip
    np.testing.assert_allclose(result["time"][1 : len(t) + 1], t + INTERVAL, atol=1e-9)
    return result[1 : len(t) + 1]


def _columns(result, name):
    return np.column_stack([result[f"{name}_{wheel}"] for wheel in WHEELS])


def test_fmpy_validates_the_fmu(fmu):
    """FMPy's validation (schema, variable names, model structure, start values, units)
    finds no problem; the archive is a source FMU: modelDescription.xml, sources/ with the
    buildDescription.xml that names every C file it holds."""
    generated, _ = fmu
    assert validate_fmu(str(generated.path)) == []
    with zipfile.ZipFile(generated.path) as archive:
        names = set(archive.namelist())
    assert "modelDescription.xml" in names and "sources/buildDescription.xml" in names
    assert {f"sources/{name}" for name in generated.sources} <= names
    assert not any(name.startswith("binaries/") for name in names)


def test_model_description_is_the_declarations(fmu):
    """The inputs are the KF's channels (rate derivatives derived) and the wheel channels, the
    parameters every field of the run-time parameter struct, the mass-centre ones constant;
    each start value is the compiled library's default, read back through the FMU."""
    generated, unzipped = fmu
    description = fmpy.read_model_description(str(generated.path))
    by_causality = {}
    for variable in description.modelVariables:
        by_causality.setdefault(variable.causality, []).append(variable)
    assert [v.name for v in by_causality["input"]] == [*FMU_INPUTS, *WHEEL_INPUTS]
    assert [v.name for v in by_causality["output"]] == [*OUTPUTS, "status", "faults"]
    tunable = [v.name for v in by_causality["parameter"]]
    assert tunable == [name for name in PARAMETERS.names() if name not in MASS_CENTRE_INPUTS]
    assert [v.name for v in by_causality["local"]] == [
        name for name in PARAMETERS.names() if name in MASS_CENTRE_INPUTS
    ]
    assert float(description.coSimulation.fixedInternalStepSize) == INTERVAL
    slave = _instance(unzipped, description)
    try:
        parameters = by_causality["parameter"] + by_causality["local"]
        values = slave.getFloat64([v.valueReference for v in parameters])
        assert values == [float(v.start) for v in parameters]  # exact: repr round trip
    finally:
        slave.freeInstance()


@pytest.mark.parametrize("which", ["clean", "gaps"])
def test_fmu_equals_python(fmu, logs, which):
    """F_z, F_x, F_y and their σ through the FMU equal the Python method's to 1e-9 N
    (measured 4e-11 N: the same operations, the library's fixed interval against the log's
    t[k] - t[k-1]), and the status bits are the same bits; with gaps some of them fire."""
    _, unzipped = fmu
    path, frame = logs[which]
    result = _simulate(unzipped, frame)
    python = build("tyre-forces", load_vehicle(example_vehicle_path())).run(read_log(path))
    for name, values in (("fz", python.loads), ("fz_std", python.std), ("fx", python.fx),
                         ("fx_std", python.fx_std), ("fy", python.fy),
                         ("fy_std", python.fy_std)):  # fmt: skip
        assert_c_equals_python(_columns(result, name), values, rtol=0, atol=1e-9, what=name)
    np.testing.assert_array_equal(result["status"], python.flags)
    if which == "gaps":
        assert np.count_nonzero(python.flags) > 20


def test_tunable_parameter_acts_as_set_param(fmu, logs):
    """A spring set through FMPy (its overrides go through PREFIX_set_param, the derived roll
    split recomputed) gives the Python method's outputs for a file with that spring to 1e-9 N;
    and they are not the default spring's."""
    _, unzipped = fmu
    path, frame = logs["clean"]
    spring = 75000.0
    result = _simulate(unzipped, frame, {"spring_front": spring})
    vehicle = load_vehicle(example_vehicle_path())
    front = dataclasses.replace(vehicle.suspension.front, spring_rate=spring)
    edited = vehicle.replace(suspension=dataclasses.replace(vehicle.suspension, front=front))
    python = build("tyre-forces", edited).run(read_log(path))
    for name, values in (("fz", python.loads), ("fz_std", python.std), ("fx", python.fx),
                         ("fy", python.fy)):  # fmt: skip
        assert_c_equals_python(_columns(result, name), values, rtol=0, atol=1e-9, what=name)
    default = _simulate(unzipped, frame)
    assert np.max(np.abs(_columns(result, "fz") - _columns(default, "fz"))) > 1.0


def _instance(unzipped, description, messages=None):
    """An instantiated FMU of the folder (FMPy's FMI 3.0 co-simulation class)."""
    slave = FMU3Slave(
        guid=description.guid, unzipDirectory=str(unzipped),
        modelIdentifier=description.coSimulation.modelIdentifier, instanceName="test",
    )  # fmt: skip

    def log(environment, status, category, message):
        if messages is not None:
            messages.append(message.decode())

    slave.instantiate(logMessage=log)
    return slave


@pytest.mark.parametrize(
    ("name", "value", "reason"),
    [
        ("sprung_mass", 1500.0, "fixed: it moves the mass centre"),
        ("spring_front", float("nan"), "not finite"),
        ("initial_std", -1.0, "out of its range"),
    ],
)
def test_refused_parameter_leaves_the_previous_value(fmu, name, value, reason):
    """A value the library refuses (set_param's statuses, init's checks) is an fmi3Error with
    a message naming the parameter and why; the parameter keeps its previous value."""
    generated, unzipped = fmu
    description = fmpy.read_model_description(str(generated.path))
    variable = next(v for v in description.modelVariables if v.name == name)
    messages = []
    slave = _instance(unzipped, description, messages)
    try:
        slave.enterInitializationMode(startTime=0.0)
        with pytest.raises(fmpy.fmi1.FMICallException):
            slave.setFloat64([variable.valueReference], [value])
        assert any(message.startswith(f"{name}: ") and reason in message
                   for message in messages), messages  # fmt: skip
        assert slave.getFloat64([variable.valueReference]) == [float(variable.start)]
    finally:
        slave.freeInstance()


@pytest.mark.parametrize("precision", list(Precision))
def test_wrapper_compiles_under_the_strict_flags(tmp_path, precision):
    """The FMI wrapper compiles under the project's strict warning flags (warnings as errors,
    conversions included: its variables are Float64 over a library in either precision) with
    FMPy's FMI 3.0 headers, as the library's own sources do (tests/estimators/codegen)."""
    generated = generate_fmu(example_vehicle_path(), tmp_path, CodegenOptions(precision=precision))
    with zipfile.ZipFile(generated.path) as archive:
        archive.extractall(tmp_path / "unzipped")
    wrapper = tmp_path / "unzipped" / "sources" / generated.sources[-1]
    assert wrapper.name.endswith("_fmu.c")
    headers = f"-I{fmpy.__path__[0]}/c-code"
    compile_c(tmp_path / "fmu.o", [wrapper], (*STRICT_CFLAGS, "-fPIC", "-c"), includes=(headers,),
              libraries=())  # fmt: skip


def _after_steps(unzipped, description, inputs, steps):
    """The real outputs of a fresh instance after communication steps of the sizes
    ``steps`` from t = 0, its inputs held at ``inputs`` (name: value)."""
    by_name = {v.name: v.valueReference for v in description.modelVariables}
    slave = _instance(unzipped, description)
    try:
        slave.enterInitializationMode(startTime=0.0)
        slave.setFloat64([by_name[name] for name in inputs], list(inputs.values()))
        slave.exitInitializationMode()
        t = 0.0
        for h in steps:
            slave.doStep(t, h)
            t += h
        return slave.getFloat64([by_name[name] for name in OUTPUTS])
    finally:
        slave.freeInstance()


def test_the_fixed_internal_step_runs_each_sample_once(fmu, logs):
    """Samples lie at startTime + k * interval, and each runs in the communication step that
    holds it: one step of two intervals, two of one and four of half an interval give the same
    outputs (the library run twice on the held inputs), and they are not those of one sample."""
    generated, unzipped = fmu
    description = fmpy.read_model_description(str(generated.path))
    _, frame = logs["clean"]
    names = [name for name in (*FMU_INPUTS, *WHEEL_INPUTS) if name in frame.columns]
    inputs = {name: float(frame[name].iloc[400]) for name in names}
    two = _after_steps(unzipped, description, inputs, [2 * INTERVAL])
    assert _after_steps(unzipped, description, inputs, [INTERVAL, INTERVAL]) == two
    assert _after_steps(unzipped, description, inputs, [INTERVAL / 2] * 4) == two
    assert _after_steps(unzipped, description, inputs, [INTERVAL]) != two


def _run_log(unzipped, description, frame, change=None):
    """The FMU stepped through the log sample by sample with FMPy's FMI 3.0 calls; ``change``
    (sample, name, value): a tunable parameter set in step mode before that sample."""
    by_name = {v.name: v.valueReference for v in description.modelVariables}
    names = [name for name in (*FMU_INPUTS, *WHEEL_INPUTS) if name in frame.columns]
    references = [by_name[name] for name in names]
    values = frame[names].to_numpy()
    slave = _instance(unzipped, description)
    rows = []
    try:
        t = frame["t"].to_numpy()
        slave.enterInitializationMode(startTime=t[0])
        slave.exitInitializationMode()
        for k in range(len(t)):
            if change is not None and k == change[0]:
                slave.setFloat64([by_name[change[1]]], [change[2]])
            slave.setFloat64(references, list(values[k]))
            slave.doStep(t[0] + k * INTERVAL, INTERVAL)
            rows.append(slave.getFloat64([by_name[name] for name in OUTPUTS]))
    finally:
        slave.freeInstance()
    return np.array(rows)


def test_a_tunable_parameter_set_in_step_mode_acts_from_the_next_sample(fmu, logs):
    """Stepped with FMPy's own calls, the FMU gives what ``simulate_fmu`` gives (exactly: the
    same inputs, the same code); a spring set in step mode leaves the samples before it as
    they were and changes the loads from that sample on."""
    generated, unzipped = fmu
    description = fmpy.read_model_description(str(generated.path))
    _, frame = logs["clean"]
    plain = _run_log(unzipped, description, frame)
    simulated = _simulate(unzipped, frame)
    np.testing.assert_array_equal(plain, np.column_stack([simulated[name] for name in OUTPUTS]))
    changed = _run_log(unzipped, description, frame, (600, "spring_front", 75000.0))
    np.testing.assert_array_equal(changed[:600], plain[:600])
    fz = slice(0, len(WHEELS))
    assert np.max(np.abs(changed[600:, fz] - plain[600:, fz])) > 1.0
