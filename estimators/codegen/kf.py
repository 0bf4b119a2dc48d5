"""Generate the two-stage KF as a self-contained, allocation-free C99 library.

The C step is emitted from the CasADi step Function the Python filter runs
(:func:`wheelload.estimators.kf.step.step_function`), so a change of the
suspension or equilibrium model in ``wheelload.models`` changes the C with no
other edit. The covariance is kept in symmetric storage (upper triangle, row
by row); the step reads only that triangle of ``P``.

Besides the single-filter ``wheelload_kf_step``, the library has
``wheelload_kf_step_batch``: ``n`` independent filters side by side (struct
of arrays), the same kernel statements with the single step's branches as
selects, so that gcc vectorises the loop over filters when built with
:data:`FAST_CFLAGS` (the generated Makefile's ``make fast`` explains each
flag). Built with the same flags, both give the same numbers; with the
strict flags they are bit-identical.

With runtime parameters, ``wheelload_kf_set_param`` sets a calibration value and recomputes
the parameters derived from it (the static loads, the default roll split) with C emitted from
the models' own derivation (:mod:`~wheelload.estimators.codegen.runtime_parameters`): a spring
set at run time gives the Python filter of the vehicle file with that spring. It makes
``wheelload_kf_init``'s checks (each field's domain and the relations between fields, one
declaration: :data:`~wheelload.estimators.codegen.runtime_parameters.PARAMETERS`) and keeps
the previous value when it refuses one.

Any log rate: the step computes everything that depends on the interval from each call's
``dt``; the nominal interval of the measurement noise is the run-time parameter
``sample_interval`` (``CodegenOptions.sample_interval`` its default), and a step faster
than it over ``interval_band`` is refused with ``StepFlag.INTERVAL_SHORT`` and counted in
the state, as the Python step does. The rate-derivative filter's gain is computed at run
time for the nominal interval.

Files written to the output folder, for prefix ``wheelload_kf``:
``wheelload_kf.h``, ``wheelload_kf.c`` (the library: depends on libm only),
``wheelload_kf_example.c`` (CSV log in, CSV estimates out),
``wheelload_kf_selftest.c`` (long-run check and timing), a ``Makefile`` and the MISRA
C:2012 deviation record ``MISRA_DEVIATIONS.md`` (:mod:`~wheelload.estimators.codegen.deviations`).

Example
-------
>>> library = generate(example_vehicle_path(), "out/c", CodegenOptions(precision=Precision.FLOAT))
>>> library.header.name
'wheelload_kf.h'
"""

from __future__ import annotations

import enum
import hashlib
import re
import string
import subprocess
from dataclasses import dataclass
from importlib import resources
from importlib.metadata import version
from pathlib import Path

import casadi as ca
import numpy as np

from wheelload.estimators.codegen.deviations import KF_DEVIATIONS, write_deviation_record
from wheelload.estimators.codegen.runtime_parameters import (
    check_defaults,
    derivation_substitutions,
    runtime_fields,
)
from wheelload.estimators.guards.settings import FAULT_CHANNELS
from wheelload.estimators.kernels.c_emitter import Precision, emit_statements, flop_count, literal
from wheelload.estimators.kf.rewind import DEFAULT_CHECKPOINTS, TIMED_INTERVAL_BAND
from wheelload.estimators.kf.step import step_function
from wheelload.estimators.kf.step_cache import STEP_INPUT_NAMES, STEP_NAME, STEP_OUTPUT_NAMES
from wheelload.estimators.kf.tuning import DEFAULT_SAMPLE_INTERVAL, TUNING, tuning_vector
from wheelload.estimators.logs.output_files import write_text
from wheelload.estimators.logs.signals import RateDerivativeFilter
from wheelload.estimators.result import StepFlag
from wheelload.models import (
    INPUTS,
    OPTIONAL_INPUTS,
    WHEELS,
    ModelParameters,
    Vehicle,
    load_vehicle,
)
from wheelload.models.inputs import input_description
from wheelload.models.runtime.build_folder import cached_object

#: Upper triangle of the 4 x 4 covariance, row by row: the symmetric storage.
PACKED = tuple((i, j) for i in range(4) for j in range(i, 4))
#: gcc flags the generated code compiles clean under, in both precisions.
STRICT_CFLAGS = (
    "-std=c99", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Wdouble-promotion", "-Wconversion",
    "-Werror",
)  # fmt: skip
#: The speed build (generated Makefile's FAST_CFLAGS, where each flag is explained):
#: vectorises the batched step, FMA contraction and shared reciprocals stated, no -ffast-math.
FAST_CFLAGS = (
    "-std=c99", "-O3", "-march=native", "-ffp-contract=fast", "-freciprocal-math",
    "-fno-math-errno", "-fno-trapping-math", "-fno-thread-jumps", "-fno-tree-pre",
    "-Wall", "-Wextra", "-Wpedantic", "-Wdouble-promotion", "-Wconversion", "-Werror",
)  # fmt: skip


class ParamMode(enum.Enum):
    """Where the calibration lives in the generated code."""

    BAKED = "baked"  # constants folded into the step
    RUNTIME = "runtime"  # fields of the parameter struct


@dataclass(frozen=True, kw_only=True)
class CodegenOptions:
    """Precision, parameter handling and C symbol prefix of the generated library."""

    precision: Precision = Precision.DOUBLE
    params: ParamMode = ParamMode.RUNTIME
    prefix: str = "wheelload_kf"
    sample_interval: float = DEFAULT_SAMPLE_INTERVAL  # s, the logger's nominal interval
    branch_free: bool = True  # selects in branch-free forms (False: plain C99 selects)
    tyre_forces: bool = False  # also the tyre-force step (PREFIX_tyre.h/.c, codegen.tyre)

    def __post_init__(self) -> None:
        if not 0.0 < self.sample_interval < 1e6:
            raise ValueError(f"sample interval must be > 0 s, got {self.sample_interval}")
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", self.prefix):
            raise ValueError(f"prefix '{self.prefix}' is not a C identifier")


@dataclass(frozen=True)
class GeneratedLibrary:
    """Paths of the generated files and the kernel Function they were emitted from."""

    header: Path
    source: Path
    example: Path
    selftest: Path
    makefile: Path
    kernel: ca.Function
    tyre: tuple[Path, Path] | None = None  # PREFIX_tyre.h, PREFIX_tyre.c (tyre_forces)

    @property
    def flops(self) -> int:
        """Arithmetic operations of one step of the kernel."""
        return flop_count(self.kernel)


def calibration_names() -> tuple[str, ...]:
    """Fields of the runtime parameter struct: model parameters, tuning, initial std."""
    return runtime_fields()


def packed(P: ca.SX) -> ca.SX:
    """The upper triangle of ``P`` in :data:`PACKED` order."""
    return ca.vertcat(*[P[i, j] for i, j in PACKED])


def unpacked(values: ca.SX) -> ca.SX:
    """The symmetric 4 x 4 matrix of a :data:`PACKED` vector."""
    where = {pair: k for k, pair in enumerate(PACKED)}
    return ca.vertcat(
        *[ca.horzcat(*[values[where[min(i, j), max(i, j)]] for j in range(4)]) for i in range(4)]
    )


def kernel_function(
    step: ca.Function,
    mode: ParamMode,
    p: np.ndarray,
    tuning: np.ndarray,
) -> ca.Function:
    """The step on symmetric storage, without the outputs the C library does not use.

    ``kernel(x, P[10], m, u, u_valid, dt[, p, tuning]) -> (x_next, P_next[10],
    m_next, std, residual, used, status, fault_statistic, fault, mass_properties,
    mass_properties_std)``; with
    :attr:`ParamMode.BAKED` the numeric ``p`` and ``tuning`` are substituted
    so that CasADi folds the constants.
    """
    x = ca.SX.sym("x", 4)
    P = ca.SX.sym("P", len(PACKED))
    m = ca.SX.sym("m", step.nnz_in(STEP_INPUT_NAMES.index("m")))
    u = ca.SX.sym("u", step.nnz_in(STEP_INPUT_NAMES.index("u")))
    valid = ca.SX.sym("u_valid", step.nnz_in(STEP_INPUT_NAMES.index("u_valid")))
    dt = ca.SX.sym("dt")
    inputs = [x, P, m, u, valid, dt]
    if mode is ParamMode.RUNTIME:
        p_in, tuning_in = ca.SX.sym("p", p.size), ca.SX.sym("tuning", tuning.size)
        inputs += [p_in, tuning_in]
    else:
        p_in, tuning_in = ca.DM(p), ca.DM(tuning)
    named = dict(zip(STEP_OUTPUT_NAMES, step(x, unpacked(P), m, u, valid, dt, p_in, tuning_in)))
    named["P_next"] = packed(named["P_next"])
    return ca.Function(
        f"{step.name()}_kernel",
        inputs,
        # Dense: an entry the baked values make exactly zero (a payload moment whose prior
        # spread is 0) keeps its place in the state arrays.
        ca.cse([ca.densify(named[name]) for name in KERNEL_OUTPUTS]),
        ["x", "P", "m", "u", "u_valid", "dt", "p", "tuning"][: len(inputs)],
        list(KERNEL_OUTPUTS),
    )


#: Inputs of the C kernel, in order (``p`` and ``tuning`` with runtime parameters).
KERNEL_INPUTS = ("x", "P", "m", "u", "u_valid", "dt", "p", "tuning")
#: Kernel inputs that hold exactly 0 or 1 (the step sets ``u_valid`` to ONE or ZERO).
BOOLEAN_INPUTS = (KERNEL_INPUTS.index("u_valid"),)
#: Outputs of the C kernel, in order.
KERNEL_OUTPUTS = (
    "x_next", "P_next", "m_next", "std", "residual", "used", "status", "fault_statistic", "fault",
    "mass_properties", "mass_properties_std",
)  # fmt: skip
#: Kernel outputs the batched step does not report (the single step does).
_SINGLE_STEP_ONLY = ("mass_properties", "mass_properties_std")


def representable(values: np.ndarray, precision: Precision) -> np.ndarray:
    """``values`` saturated to the largest finite number of ``precision``.

    A calibration value beyond the float range (e.g. a process noise density
    of 1e300) becomes ``FLT_MAX``; the step's covariance ceiling then acts
    as it would on the double value.
    """
    largest = np.finfo(np.float32 if precision is Precision.FLOAT else np.float64).max
    return np.clip(np.asarray(values, float), -float(largest), float(largest))


def calibration_values(vehicle: Vehicle, options: CodegenOptions) -> dict[str, float]:
    """The fields of ``PREFIX_default_params`` by name (:func:`calibration_names`): the
    vehicle's model parameters, its tuning at the options' sample interval and reset's
    initial std, each :func:`representable` in the options' precision."""
    p = ModelParameters.from_vehicle(vehicle).vector()
    tuning = tuning_vector(vehicle, options.sample_interval)
    values = np.array([*p, *tuning, vehicle.filter.initial_std])
    return dict(zip(calibration_names(), representable(values, options.precision)))


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _template(name: str) -> string.Template:
    text = (resources.files("wheelload.estimators.codegen") / "templates" / name).read_text("utf-8")
    return string.Template(text)


def _substitutions(
    vehicle_path: Path,
    vehicle: Vehicle,
    options: CodegenOptions,
    step: ca.Function,
    kernel: ca.Function,
) -> dict[str, str]:
    values = calibration_values(vehicle, options)
    rate_filter = RateDerivativeFilter.of(vehicle)
    precision, prefix = options.precision, options.prefix
    real = precision.value
    runtime = options.params is ParamMode.RUNTIME
    check_defaults(values, runtime)
    fields = calibration_names() if runtime else ("initial_std",)

    def param(name: str) -> str:
        return f"params->{name}" if runtime else literal(values[name], precision)

    inputs = ["x[{}]", "P[{}]", "m[{}]", "u[{}]", "u_valid[{}]", "dt"]
    if runtime:
        inputs += [
            [f"params->{n}" for n in ModelParameters.names()],
            [f"params->{n}" for n in TUNING.names()],
        ]
    body = emit_statements(
        kernel,
        inputs,
        [f"{name}[{{}}]" for name in KERNEL_OUTPUTS],
        precision,
        f"{prefix}_real",
        boolean_inputs=BOOLEAN_INPUTS,
        branch_free=options.branch_free,
    )
    # One domain test per field (runtime_parameters.domain_code, set_param's too); then the
    # relations between fields: 1 + the number of fields.
    checks = [
        f"    if (!param_in_domain({k}, params->{name})) {{\n        return {k + 1};\n    }}"
        for k, name in enumerate(fields)
    ]
    if runtime:
        checks.append(
            f"    if (!relations_hold(params)) {{\n        return {len(fields) + 1};\n    }}"
        )
    flags = [f"#define {prefix.upper()}_FLAG_{flag.name} {flag.value}u" for flag in StepFlag]
    return {
        "prefix": prefix,
        "PREFIX": prefix.upper(),
        "real": real,
        "real_c": "x##f" if precision is Precision.FLOAT else "x",
        "sqrt": "sqrtf" if precision is Precision.FLOAT else "sqrt",
        "fabs": "fabsf" if precision is Precision.FLOAT else "fabs",
        "real_max": "FLT_MAX" if precision is Precision.FLOAT else "DBL_MAX",
        "digits": "%.9g" if precision is Precision.FLOAT else "%.17g",
        "precision": real,
        "params_mode": options.params.value,
        "single_precision": str(int(precision is Precision.FLOAT)),
        "runtime_params": str(int(runtime)),
        "wheelload_version": version("wheelload"),
        "casadi_version": ca.__version__,
        "vehicle_name": vehicle_path.name,
        "vehicle_sha256": _sha256(vehicle_path.read_bytes()),
        "model_sha256": _sha256(step.serialize().encode()),
        "step_name": step.name(),
        "flops": str(flop_count(kernel)),
        "kernel_flops": str(flop_count(kernel)),
        "n_params": str(len(fields)),
        "params_note": (
            "Every calibration value; change them without regenerating."
            if runtime
            else "Vehicle and tuning are baked into the step; only the initial "
            "standard deviation of reset is here."
        ),
        "param_fields": "\n".join(f"    {prefix}_real {name};" for name in fields),
        "param_defaults": "\n".join(
            f"    {literal(values[name], precision)}, /* {name} */" for name in fields
        ),
        "param_names": "\n".join(f'    "{name}",' for name in fields),
        "param_cases": "\n".join(
            f"    case {k}:\n        return &params->{name};" for k, name in enumerate(fields)
        ),
        "param_checks": "\n".join(checks),
        "flag_defines": "\n".join(flags),
        "n_inputs": str(len(INPUTS)),
        "n_used": str(len(StepFlag.update_flags())),
        "input_fields": "\n".join(
            f"    {prefix}_real {name}; /* {input_description(name)} */" for name in INPUTS
        ),
        "input_names": "\n".join(f'    "{name}",' for name in INPUTS),
        "rate_jerk_density": literal(float(rate_filter.jerk_density), precision),
        "rate_gyro_noise_density": literal(float(rate_filter.gyro_noise_density), precision),
        "rate_interval": literal(float(options.sample_interval), precision),
        "nominal_interval": param("sample_interval"),
        "interval_option": repr(float(options.sample_interval)),
        "interval_band": param("interval_band"),
        "short_index": str(StepFlag.guard_flags().index(StepFlag.INTERVAL_SHORT)),
        "input_optional": ", ".join(str(int(name in OPTIONAL_INPUTS)) for name in INPUTS),
        "input_cases": "\n".join(
            f"    case {k}:\n        return &input->{name};" for k, name in enumerate(INPUTS)
        ),
        "input_copy": "\n".join(f"    u[{k}] = input->{name};" for k, name in enumerate(INPUTS)),
        "update_flags": ", ".join(f"{flag.value}u" for flag in StepFlag.update_flags()),
        "guard_flags": ", ".join(f"{flag.value}u" for flag in StepFlag.guard_flags()),
        "n_monitor": str(kernel.nnz_in(2)),
        "n_status": str(kernel.nnz_out(KERNEL_OUTPUTS.index("status"))),
        "n_faults": str(len(FAULT_CHANNELS)),
        "fault_channels": ", ".join(FAULT_CHANNELS),
        "kernel_params_doc": ", p, tuning" if runtime else " (vehicle and tuning baked in)",
        "n_checkpoints": str(DEFAULT_CHECKPOINTS),
        "timed_interval_band": repr(TIMED_INTERVAL_BAND),
        "speed_index": str(INPUTS.index("vx")),
        "kernel_params_arg": f", const {prefix}_params *params" if runtime else "",
        "kernel_params_call": ", params" if runtime else "",
        "unused_params": "" if runtime else "    (void)params;",
        "static_loads": "\n".join(
            f"    state->x[{k}] = {param(f'static_{wheel}')};" for k, wheel in enumerate(WHEELS)
        ),
        "kernel_body": _indent(body),
        "strict_cflags": " ".join(STRICT_CFLAGS),
        "fast_cflags": " ".join(FAST_CFLAGS),
        "batch_params": "\n".join(
            f"    const {prefix}_real param_{name} = params->{name};"
            for name in (*ModelParameters.names(), *TUNING.names())
            if runtime
        ),
        "batch_rows": _batch_rows(kernel, prefix),
        "batch_body": _indent(_batch_body(kernel, runtime, precision, prefix), 2),
        **derivation_substitutions(vehicle, runtime, precision, prefix, values),
    }


def _indent(text: str, levels: int = 1) -> str:
    return "\n".join(f"{'    ' * levels}{line}" for line in text.splitlines())


def _batch_rows(kernel: ca.Function, prefix: str) -> str:
    """Declarations of one ``restrict`` pointer per row of the batch's arrays.

    Row ``k`` of an array of ``n`` filters starts at ``k * n``; a pointer per
    row lets the compiler see that the rows do not overlap (it cannot prove
    it for offsets ``k * n`` with ``n`` unknown), so it vectorises the loop.
    """
    rows = {
        "x": ("x", 4, False),
        "P": ("P", 10, False),
        "monitor": ("monitor", kernel.nnz_in(KERNEL_INPUTS.index("m")), False),
        "u": ("u", kernel.nnz_in(KERNEL_INPUTS.index("u")), True),
        "std_out": ("std_out", 4, False),
        "residual_out": ("residual_out", 3, False),
        "statistic_out": ("statistic_out", len(FAULT_CHANNELS), False),
    }
    lines = []
    for name, (array, size, const) in rows.items():
        qualifier = "const " if const else ""
        for k in range(size):
            offset = ("", " + n")[k] if k < 2 else f" + {k} * n"  # no x + 0 * n (rule 2.2)
            lines.append(f"    {qualifier}{prefix}_real *restrict {name}_{k} = {array}{offset};")
    return "\n".join(lines)


def _batch_body(kernel: ca.Function, runtime: bool, precision: Precision, prefix: str) -> str:
    """Loop body of the batched step: filter ``b`` of ``n``, struct-of-arrays storage.

    The same kernel statements as the single step, on scalars; the single
    step's branches (input validity, acceptance of the result, flags) become
    selects so that gcc can vectorise the loop over ``b``.
    """
    real = f"{prefix}_real"
    zero, half = literal(0.0, precision), literal(0.5, precision)
    n_u = kernel.nnz_in(KERNEL_INPUTS.index("u"))
    lines = [f"const {real} dt_b = dt_in[b];"]
    lines += [f"const {real} P_old{k} = P_{k}[b];" for k in (0, 4, 7, 9)]
    for k in range(n_u):
        lines.append(f"const {real} raw{k} = u_{k}[b];")
        lines.append(f"const {real} valid{k} = FINITE(raw{k}) ? ONE : ZERO;")
        lines.append(f"const {real} value{k} = FINITE(raw{k}) ? raw{k} : ZERO;")
    sizes = {name: kernel.nnz_out(i) for i, name in enumerate(KERNEL_OUTPUTS)}
    update_flags = StepFlag.update_flags()[: sizes["used"]]
    guard_flags = StepFlag.guard_flags()[: sizes["status"]]
    for name, size in sizes.items():
        lines.append(f"{real} {', '.join(f'{name}{k}' for k in range(size))};")
    inputs = [
        "x_{}[b]",
        "P_{}[b]",
        "monitor_{}[b]",
        [f"value{k}" for k in range(n_u)],
        [f"valid{k}" for k in range(n_u)],
        "dt_b",
    ]
    if runtime:  # copied into locals before the loop (batch_params): no aliasing with stores
        inputs += [
            [f"param_{n}" for n in ModelParameters.names()],
            [f"param_{n}" for n in TUNING.names()],
        ]
    lines.append("{")
    body = emit_statements(
        kernel,
        inputs,
        [f"{name}{{}}" for name in sizes],
        precision,
        real,
        boolean_inputs=BOOLEAN_INPUTS,
    )
    lines += [f"    {line}" for line in body.splitlines()]
    lines += [f"    (void){name}{k};" for name in _SINGLE_STEP_ONLY for k in range(sizes[name])]
    lines.append("}")
    finite = [
        f"FINITE({name}{k})"
        for name in (
            "x_next",
            "P_next",
            "std",
            "residual",
            "m_next",
            "fault_statistic",
            *_SINGLE_STEP_ONLY,
        )  # the single step's acceptance: every output finite
        for k in range(sizes[name])
    ]
    positive = [f"P_next{k} > {zero}" for k in (0, 4, 7, 9)]
    # Acceptance as a real 0/1 chained through selects (vectorises as blends).
    lines.append(f"{real} accepted = (dt_b > ZERO) ? ONE : ZERO;")
    lines.append("accepted = FINITE(dt_b) ? accepted : ZERO;")
    lines += [f"accepted = ({c}) ? accepted : ZERO;" for c in finite + positive]
    for name, state in (("x_next", "x"), ("P_next", "P"), ("m_next", "monitor")):
        for k in range(sizes[name]):
            lines.append(f"{state}_{k}[b] = accepted > HALF ? {name}{k} : {state}_{k}[b];")
    for k, diagonal in enumerate((0, 4, 7, 9)):
        lines.append(f"std_out_{k}[b] = accepted > HALF ? std{k} : SQRT(P_old{diagonal});")
    for name, target in (("residual", "residual_out"), ("fault_statistic", "statistic_out")):
        for k in range(sizes[name]):
            lines.append(f"{target}_{k}[b] = accepted > HALF ? {name}{k} : {zero};")
    # Flags summed as exact small integers in the real type, low and high 16
    # bits apart (each sum below 2^16, exact in float), then converted: no
    # integer or boolean logic in the loop.
    flags = [
        *[(f"used{k} < {half}", flag.value) for k, flag in enumerate(update_flags)],
        *[(f"status{k} > {half}", flag.value) for k, flag in enumerate(guard_flags)],
    ]
    rejected = sum(flag.value for flag in update_flags) | StepFlag.STEP_REJECTED.value
    for half_name, shift in (("low", 0), ("high", 16)):
        terms = [
            f"({condition} ? {literal((value >> shift) & 0xFFFF, precision)} : {zero})"
            for condition, value in flags
            if (value >> shift) & 0xFFFF
        ] or [zero]
        lines.append(
            f"const {real} flags_{half_name} = accepted > HALF ? ("
            + "\n    + ".join(terms)
            + f") : {literal((rejected >> shift) & 0xFFFF, precision)};"
        )
    lines.append(
        "flags_out[b] = (uint32_t)(int32_t)flags_low | ((uint32_t)(int32_t)flags_high << 16);"
    )
    fault_bits = [
        f"(fault{k} > {half} ? {literal(1 << k, precision)} : {zero})"
        for k in range(sizes["fault"])
    ]
    lines.append(
        f"const {real} fault_sum = accepted > HALF ? (" + " + ".join(fault_bits) + f") : {zero};"
    )
    lines.append("faults_out[b] = (uint32_t)(int32_t)fault_sum;")
    return "\n".join(lines)


def generate(
    vehicle_path: str | Path,
    out_dir: str | Path,
    options: CodegenOptions | None = None,
    step: ca.Function | None = None,
    *,
    allow_unusual: bool = False,
) -> GeneratedLibrary:
    """Write the C library for a vehicle file; ``step`` defaults to :func:`step_function`.

    ``step`` may be built with alternative model Functions
    (``step_function(suspension=..., equilibrium=...)``); the emitted C
    follows it. ``allow_unusual``: accept a vehicle outside the physical ranges.
    """
    options = options or CodegenOptions()
    vehicle_path = Path(vehicle_path)
    out_dir = Path(out_dir)
    step = step or step_function(name=STEP_NAME)
    vehicle = load_vehicle(vehicle_path, allow_unusual=allow_unusual)
    kernel = kernel_function(
        step,
        options.params,
        representable(ModelParameters.from_vehicle(vehicle).vector(), options.precision),
        representable(tuning_vector(vehicle, options.sample_interval), options.precision),
    )
    values = _substitutions(vehicle_path, vehicle, options, step, kernel)
    prefix = options.prefix
    values.update(_tyre_fields(vehicle, options))
    out_dir.mkdir(parents=True, exist_ok=True)
    targets = {
        "library.h": out_dir / f"{prefix}.h",
        "library.c": out_dir / f"{prefix}.c",
        "example.c": out_dir / f"{prefix}_example.c",
        "selftest.c": out_dir / f"{prefix}_selftest.c",
        "Makefile": out_dir / "Makefile",
    }
    tyre = {"tyre.h": out_dir / f"{prefix}_tyre.h", "tyre.c": out_dir / f"{prefix}_tyre.c"}
    for template, target in {**targets, **(tyre if options.tyre_forces else {})}.items():
        write_text(target, _template(template).substitute(values), replace=True)
    write_deviation_record(out_dir, KF_DEVIATIONS, prefix)
    return GeneratedLibrary(
        *targets.values(), kernel=kernel,
        tyre=tuple(tyre.values()) if options.tyre_forces else None,
    )  # fmt: skip


def _tyre_fields(vehicle: Vehicle, options: CodegenOptions) -> dict[str, str]:
    """Template fields of the tyre-force step's files and of its part of the example and
    Makefile (empty parts without ``tyre_forces``)."""
    from wheelload.estimators.codegen.tyre import tyre_substitutions
    from wheelload.estimators.family.tyres.step import WHEEL_INPUTS

    prefix = options.prefix
    if not options.tyre_forces:
        return {"tyre_forces": "0", "wheel_channel_names": "", "tyre_columns": "",
                "tyre_example_note": "", "tyre_objects": "", "tyre_rule": "",
                "tyre_refusal_report": ""}  # fmt: skip
    columns = [f"{name}_{wheel}" for name in ("fx", "fx_std", "fy", "fy_std") for wheel in WHEELS]
    columns.append("high_slip")
    return {
        **tyre_substitutions(vehicle, options.sample_interval, options.precision, prefix),
        "tyre_forces": "1",
        "wheel_channel_names": "\n".join(f'    "{name}",' for name in WHEEL_INPUTS),
        "tyre_columns": "," + ",".join(columns),
        "tyre_example_note": (
            f"\n * Built with the tyre-force step ({prefix}_tyre.h): the log needs the columns "
            f"\n * {' '.join(WHEEL_INPUTS)} too, and the estimates get\n * "
            + " ".join(f"{c}_*" for c in ("fx", "fx_std", "fy", "fy_std"))
            + " high_slip after status."
        ),
        "tyre_objects": f" {prefix}_tyre.o",
        "tyre_refusal_report": _TYRE_REFUSAL_REPORT.replace("PREFIX", prefix),
        "tyre_rule": (
            f"\n{prefix}_tyre.o: {prefix}_tyre.c {prefix}_tyre.h {prefix}.h\n"
            f"\t$(CC) $(CFLAGS) -c -o $@ {prefix}_tyre.c\n"
        ),
    }


_TYRE_REFUSAL_REPORT = """
#if TYRE_FORCES
    if (tyre.interval_refusals > 0u) {
        fprintf(stderr, "%lu tyre steps refused: their interval is not the %g s the tyre "
                "step is discretised at; regenerate with wheelload codegen --interval SECONDS"
                "\\n", (unsigned long)tyre.interval_refusals, (double)PREFIX_tyre_interval);
    }
#endif"""


def build_program(
    library: GeneratedLibrary,
    main_source: Path,
    binary: str | Path,
    *,
    compiler: str = "gcc",
    flags: tuple[str, ...] = STRICT_CFLAGS,
) -> Path:
    """Compile ``main_source`` (e.g. ``library.example``) and link it with the library, whose
    object is compiled once per text and flags (``cached_object``); errors show gcc."""
    binary = Path(binary)
    objects = [cached_object(library.source, (library.header,), (compiler, *flags))]
    if library.tyre is not None:
        objects.append(cached_object(library.tyre[1], (library.header, library.tyre[0]),
                                     (compiler, *flags)))  # fmt: skip
    command = [compiler, *flags, "-o", str(binary), str(main_source), *map(str, objects), "-lm"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{main_source}: {' '.join(command)} failed:\n{result.stderr}")
    return binary
