"""The generated KF library's run-time parameters: setting one keeps the derived ones current.

Some model parameters are derived from others (:data:`~wheelload.models.parameters.DERIVED`:
the static loads from the mass and CG, the default roll split from the springs, bars and
links). ``PREFIX_set_param`` sets a field and recomputes every derived parameter that
depends on it, with C emitted from the same CasADi Function the Python parameters take them
from (:func:`~wheelload.models.parameters.derived_function`), so a spring set at run time
gives the loads of the Python filter built from the vehicle file with that spring. Setting a
derived parameter itself pins it (a measured roll split, as the file's
``suspension.roll_split_front`` does). A parameter that enters the mass centre with
vehicle-file values the library does not hold
(:data:`~wheelload.models.parameters.MASS_CENTRE_INPUTS`) is refused with
``PREFIX_SET_FIXED``: the library is regenerated from the changed file.

The parameter struct records what the last derivation saw (``record``); ``PREFIX_init``
refuses a struct in which a source was written directly (through ``PREFIX_param_field`` or
the field), which would leave a derived parameter stale. Baked parameters have nothing to
derive at run time: only ``initial_std`` is a field.

Example
-------
>>> c = derivation_substitutions(vehicle, ParamMode.RUNTIME, Precision.DOUBLE, "wheelload_kf")
>>> "wheelload_kf_set_param" in c["derivation_code"]
True
"""

from __future__ import annotations

import enum
import math
import textwrap

import casadi as ca
import numpy as np

from wheelload.estimators.kernels.c_emitter import Precision, emit_statements, literal
from wheelload.estimators.kernels.layout import Domain, Field, Layout
from wheelload.estimators.kf.tuning import TUNING
from wheelload.models import GRAVITY, WHEELS, ModelParameters, Vehicle
from wheelload.models.parameters import (
    DERIVED,
    MASS_CENTRE_INPUTS,
    derived_function,
    derived_sources,
    following,
)

#: Bit of a record entry or field that no run-time value may change (a mass-centre input).
FIXED_BIT = 1 << 31


class SetStatus(enum.IntEnum):
    """Return values of ``PREFIX_set_param`` (``PREFIX_SET_<name>``)."""

    OK = 0
    UNKNOWN = 1  # no field of that index
    NOT_FINITE = 2  # the value, or a parameter derived from it, is not finite
    FIXED = 3  # another value of a field that moves the mass centre with file values the
    # library does not hold
    OUT_OF_RANGE = 4  # the value, or a parameter derived from it, is outside its domain
    # (PARAMETERS; the same test PREFIX_init makes)


#: The values each model parameter may take in the generated C (``PREFIX_set_param`` and
#: ``PREFIX_init`` refuse others): wide physical bounds in which the step's arithmetic stays
#: finite, in both precisions; not the vehicle file's plausibility ranges
#: (models/vehicle/plausibility.py), which a deliberate calibration may leave.
MODEL_DOMAINS: dict[str, Domain] = {
    "mass": Domain(50.0, 1e6),  # kg
    **dict.fromkeys(("lf", "lr"), Domain(1e-3, 100.0)),  # m
    **dict.fromkeys(("track_front", "track_rear"), Domain(1e-2, 100.0)),  # m
    "cg_height": Domain(0.0, 100.0),  # m
    "air_density": Domain(0.0, 100.0),  # kg/m^3
    "reference_area": Domain(0.0, 1e3),  # m^2
    **dict.fromkeys(("lift_coefficient", "drag_coefficient"), Domain(-100.0, 100.0)),
    **dict.fromkeys(("aero_x", "aero_z"), Domain(-100.0, 100.0)),  # m
    **dict.fromkeys(("spring_front", "spring_rear"), Domain(1.0, 1e9)),  # N/m
    **dict.fromkeys(("damper_push_front", "damper_pull_front", "damper_push_rear",
                     "damper_pull_rear"), Domain(0.0, 1e9)),  # N s/m
    **dict.fromkeys(("arb_rate_front", "arb_rate_rear"), Domain(0.0, 1e9)),  # N/m
    **dict.fromkeys(("arb_ratio_front", "arb_ratio_rear"), Domain(0.0, 100.0)),
    **dict.fromkeys(("static_fl", "static_fr", "static_rl", "static_rr"),
                    Domain(0.0, 1e8)),  # N, derived: checked when recomputed too
    "roll_split_front": Domain(0.0, 1.0),
    "sprung_mass": Domain(50.0, 1e6),  # kg
    "sprung_cg_height": Domain(0.0, 100.0),  # m
    **dict.fromkeys(("inertia_xx", "inertia_yy"), Domain(1e-3, 1e9)),  # kg m^2
    **dict.fromkeys(("unsprung_front", "unsprung_rear"), Domain(0.0, 1e6)),  # kg
    **dict.fromkeys(("tyre_rate_front", "tyre_rate_rear"), Domain(1.0, 1e10)),  # N/m
    **dict.fromkeys(("roll_centre_front", "roll_centre_rear"), Domain(-100.0, 100.0)),  # m
    **dict.fromkeys(("anti_brake_front", "anti_brake_rear", "anti_drive_front",
                     "anti_drive_rear"), Domain(-10.0, 10.0)),
    **dict.fromkeys(("bump_gap_front", "bump_gap_rear", "rebound_gap_front",
                     "rebound_gap_rear"), Domain(1e-6, 10.0)),  # m
    **dict.fromkeys(("stop_rate_front", "stop_rate_rear"), Domain(0.0, 1e10)),  # N/m
    **dict.fromkeys(("stop_progressive_front", "stop_progressive_rear"),
                    Domain(0.0, 1e14)),  # N/m^2
    **dict.fromkeys(("imu_x", "imu_y", "imu_z", "cg_y"), Domain(-100.0, 100.0)),  # m
    **{f"imu_r{i}{j}": Domain(-1.0, 1.0) for i in (1, 2, 3) for j in (1, 2, 3)},
    **{name: Domain(0.0, 1.0) for name in ModelParameters.names() if name.startswith("term_")},
}  # fmt: skip

#: The runtime parameter struct ``PREFIX_params``, in member order: the model parameters
#: (the step's ``p``), the tuning vector (its ``tuning``, :data:`TUNING`'s declaration), the
#: initial standard deviation of reset; each with the values it may take (its domain).
PARAMETERS = Layout(
    "params",
    (
        *[
            Field(name, doc="model parameter (models.parameters)", domain=MODEL_DOMAINS[name])
            for name in ModelParameters.names()
        ],
        *TUNING.fields,
        # No upper bound: the first step replaces reset's covariance by the ceiling.
        Field("initial_std", unit="N", file_key=("filter", "initial_std"), doc="reset's std",
              domain=Domain(1e-3)),
    ),
)  # fmt: skip


def relations_function() -> ca.Function:
    """``parameter_relations(params) -> margins``: relations between fields a calibration
    must satisfy, each as a margin that holds at or below 0 (:data:`PARAMETERS` order in):
    every static load within the step's load limit, ``|static_w| <= load_limit m g`` (else
    the reset state is one the step's load limit would refuse)."""
    values = ca.SX.sym("params", PARAMETERS.size)

    def value(name: str) -> ca.SX:
        return values[PARAMETERS.index(name)]

    limit = value("load_limit") * value("mass") * GRAVITY
    margins = [ca.fabs(value(f"static_{wheel}")) - limit for wheel in WHEELS]
    return ca.Function("parameter_relations", [values], [ca.vertcat(*margins)])


def _largest(precision: Precision) -> float:
    """The largest finite number of ``precision`` (a bound beyond it is no bound there)."""
    return float(np.finfo(np.float32 if precision is Precision.FLOAT else np.float64).max)


def domain_function(
    fields: tuple[str, ...], domains: dict[str, Domain], precision: Precision, prefix: str,
    name: str = "param_in_domain",
) -> str:  # fmt: skip
    """C ``static int NAME(int index, PREFIX_real value)``: 1 if ``value`` is finite and
    within the domain of field ``index`` (of ``fields``, ``domains`` theirs)."""
    real = f"{prefix}_real"
    cases: dict[str, list[int]] = {}
    for k, field in enumerate(fields):
        d = domains[field]
        tests = ["FINITE(value)"]
        if math.isfinite(d.low):
            tests.append(f"value {'>' if d.open_low else '>='} {literal(d.low, precision)}")
        if math.isfinite(d.high) and d.high < _largest(precision):
            tests.append(f"value {'<' if d.open_high else '<='} {literal(d.high, precision)}")
        cases.setdefault(" && ".join(tests), []).append(k)
    lines = [f"static int {name}(int index, {real} value)\n{{\n    switch (index) {{"]
    for condition, indices in cases.items():
        lines += [f"    case {k}: /* {fields[k]} */" for k in indices]
        lines.append(f"        return {condition};")
    lines.append("    default:\n        return 0;\n    }\n}")
    return "\n".join(lines)


def domain_code(fields: tuple[str, ...], runtime: bool, precision: Precision, prefix: str) -> str:
    """C of the checks ``PREFIX_init`` and ``PREFIX_set_param`` share, from the one
    declaration (:data:`PARAMETERS`' domains, :func:`relations_function`):
    ``param_in_domain(index, value)`` (1: finite and within field ``index``'s domain) and,
    with runtime parameters, ``relations_hold(params)``."""
    real = f"{prefix}_real"
    lines = [
        f"/* 1 if value is finite and within the domain of field index ({prefix}_param_names;"
        "\n * wheelload.estimators.codegen.runtime_parameters.PARAMETERS). */",
        domain_function(fields, PARAMETERS.domains(), precision, prefix),
    ]
    if runtime:
        function = relations_function()
        body = emit_statements(
            function, [[f"params->{name}" for name in fields]], ["margin[{}]"], precision, real
        )
        n = function.nnz_out(0)
        lines.append(
            f"\n/* true if the relations between fields hold (parameter_relations of\n"
            f" * wheelload.estimators.codegen.runtime_parameters: each static load within\n"
            f" * +-load_limit m g). */\nstatic bool relations_hold(const {prefix}_params *params)"
            f"\n{{\n    {real} margin[{n}];\n    int k;\n    bool hold = true;\n"
            + "\n".join(f"    {line}" for line in body.splitlines())
            + f"\n    for (k = 0; k < {n}; ++k) {{"
            "\n        hold = hold && (margin[k] <= ZERO);\n    }"
            "\n    return hold;\n}"
        )
    return "\n".join(lines)


def check_defaults(values: dict[str, float], runtime: bool) -> None:
    """Raise ``ValueError`` naming each default outside its domain, or a failed relation:
    the generated ``PREFIX_init`` would refuse the library's own defaults."""
    domains = PARAMETERS.domains()
    fields = runtime_fields() if runtime else ("initial_std",)
    bad = [f"{name} = {values[name]!r} (domain {domains[name].describe()})"
           for name in fields if not domains[name].holds(values[name])]  # fmt: skip
    if runtime:
        margins = relations_function()([values[name] for name in fields]).full().ravel()
        bad += [f"static_{wheel} beyond load_limit m g" for wheel, margin in zip(WHEELS, margins)
                if not margin <= 0.0]  # fmt: skip
    if bad:
        raise ValueError(
            f"the calibration is outside what the generated C accepts: {'; '.join(bad)}"
        )


def runtime_fields() -> tuple[str, ...]:
    """Members of the runtime parameter struct (:data:`PARAMETERS`), in order."""
    return PARAMETERS.names()


def feeds() -> dict[str, int]:
    """Per field, the bits (order of ``DERIVED``) of the derived parameters it is a source of,
    with :data:`FIXED_BIT` for a mass-centre input; fields that feed nothing are left out."""
    bits: dict[str, int] = {}
    for k, sources in enumerate(derived_sources().values()):
        for name in sources:
            bits[name] = bits.get(name, 0) | 1 << k
    for name in MASS_CENTRE_INPUTS:
        bits[name] = bits.get(name, 0) | FIXED_BIT
    return bits


def record_entries() -> dict[str, int]:
    """The recorded fields (field order) and the bits each concerns: a derived parameter its
    own, a source those it feeds, a mass-centre input :data:`FIXED_BIT`."""
    bits = feeds()
    for k, name in enumerate(DERIVED):
        bits[name] = bits.get(name, 0) | 1 << k
    return {name: bits[name] for name in runtime_fields() if name in bits}


def derivation_substitutions(
    vehicle: Vehicle,
    runtime: bool,
    precision: Precision,
    prefix: str,
    values: dict[str, float],
) -> dict[str, str]:
    """Template substitutions of the derivation: header notes, struct members, defaults,
    ``PREFIX_set_param`` and init's check. ``values``: the fields' default values."""
    PREFIX = prefix.upper()
    statuses = "\n".join(
        f"#define {PREFIX}_SET_{status.name} {status.value}" for status in SetStatus
    )
    if not runtime:
        return {
            "set_statuses": statuses,
            "n_derived": "0",
            "derived_comment": _comment(
                "Derived parameters: none at run time, the vehicle and tuning are baked into "
                "the step."
            ),
            "derivation_fields": "",
            "derivation_defaults": "",
            "derivation_code": domain_code(("initial_std",), False, precision, prefix)
            + "\n\n"
            + _baked_set_param(prefix),
            "derivation_check": "",
        }
    fields = runtime_fields()
    record = record_entries()
    follow = following(vehicle)
    bits = sum(1 << DERIVED.index(name) for name in follow)
    pinned = [name for name in DERIVED if name not in follow]
    sources = derived_sources()
    note = "; ".join(f"{name} from {', '.join(sources[name])}" for name in DERIVED)
    note += f" (pinned by the vehicle file: {', '.join(pinned)})" if pinned else ""
    note = (
        f"Derived parameters, recomputed by {prefix}_set_param from their sources with the "
        f"model's own equations (wheelload.models.parameters.derived_function): {note}. Not "
        f"settable (they move the mass centre): {', '.join(MASS_CENTRE_INPUTS)}."
    )
    real = f"{prefix}_real"
    body = emit_statements(
        derived_function(),
        [[f"params->{name}" for name in ModelParameters.names()]],
        ["derived[{}]"],
        precision,
        real,
    )
    feed_bits = feeds()
    table = ", ".join(f"{feed_bits.get(name, 0)}u" for name in fields)
    code = _RUNTIME_SET_PARAM.format(
        prefix=prefix,
        PREFIX=PREFIX,
        real=real,
        body="\n".join(f"    {line}" for line in body.splitlines()),
        feeds=table,
        derived_index=", ".join(str(PARAMETERS.index(name)) for name in DERIVED),
        record_index=", ".join(str(PARAMETERS.index(name)) for name in record),
        n_record=len(record),
        fixed=f"{FIXED_BIT}u",
    )
    defaults = [f"    {bits}u, /* derived: {' '.join(follow) or 'none'} follow their sources */"]
    defaults.append(_comment(f"record: {' '.join(record)}", "    "))
    numbers = ", ".join(literal(values[name], precision) for name in record)
    defaults.append(textwrap.fill("{" + numbers + "},", 96, initial_indent="    ",
                                  subsequent_indent="     "))  # fmt: skip
    return {
        "set_statuses": statuses,
        "n_derived": str(len(DERIVED)),
        "derived_comment": _comment(note),
        "derivation_fields": _comment(
            f"Kept by {prefix}_set_param, checked by {prefix}_init; do not write. derived: bit "
            f"k set while derived parameter k ({', '.join(DERIVED)}) follows its sources; "
            f"record: the values the last derivation saw of {' '.join(record)}.",
            "    ",
        )
        + f"\n    uint32_t derived;\n    {real} record[{len(record)}];",
        "derivation_defaults": "\n".join(defaults),
        "derivation_code": domain_code(fields, True, precision, prefix) + "\n\n" + code,
        "derivation_check": _runtime_check(prefix, record),
    }


def _comment(text: str, indent: str = "") -> str:
    """``text`` as a C comment wrapped at 96 columns."""
    lines = textwrap.wrap(text, 93 - len(indent))
    body = f"\n{indent} * ".join(lines)
    return f"{indent}/* {body} */"


def _baked_set_param(prefix: str) -> str:
    PREFIX = prefix.upper()
    return f"""int {prefix}_set_param({prefix}_params *params, int index, {prefix}_real value)
{{
    {prefix}_real *field = {prefix}_param_field(params, index);
    if (field == 0) {{
        return {PREFIX}_SET_UNKNOWN;
    }}
    if (!isfinite(value)) {{
        return {PREFIX}_SET_NOT_FINITE;
    }}
    if (!param_in_domain(index, value)) {{
        return {PREFIX}_SET_OUT_OF_RANGE;
    }}
    *field = value;
    return {PREFIX}_SET_OK;
}}"""


_RUNTIME_SET_PARAM = """/* Per field: bit k if it is a source of derived parameter k; FIXED_BIT if
 * it may not be set at run time. */
#define FIXED_BIT {fixed}
static const uint32_t param_feeds[{PREFIX}_N_PARAMS] = {{{feeds}}};
/* Field index of each derived parameter and of each record entry. */
static const int derived_index[{PREFIX}_N_DERIVED] = {{{derived_index}}};
#define N_RECORD {n_record}
static const int record_index[N_RECORD] = {{{record_index}}};

/* The derived parameters of params (CasADi Function derived_parameters of
 * wheelload.models.parameters, the values the Python parameters take). */
static void {prefix}_derive(const {prefix}_params *params,
                             {real} derived[{PREFIX}_N_DERIVED])
{{
{body}
}}

int {prefix}_set_param({prefix}_params *params, int index, {real} value)
{{
    {prefix}_params changed;
    {real} derived[{PREFIX}_N_DERIVED];
    uint32_t recompute;
    int k, j;
    if (index < 0 || index >= {PREFIX}_N_PARAMS) {{
        return {PREFIX}_SET_UNKNOWN;
    }}
    if (!isfinite(value)) {{
        return {PREFIX}_SET_NOT_FINITE;
    }}
    if (!param_in_domain(index, value)) {{
        return {PREFIX}_SET_OUT_OF_RANGE;
    }}
    if ((param_feeds[index] & FIXED_BIT) != 0u) {{ /* its own value only: nothing moves */
        const bool same = value == *{prefix}_param_field(params, index);
        return same ? {PREFIX}_SET_OK : {PREFIX}_SET_FIXED;
    }}
    changed = *params;
    *{prefix}_param_field(&changed, index) = value;
    recompute = param_feeds[index] & changed.derived;
    for (k = 0; k < {PREFIX}_N_DERIVED; ++k) {{
        if (derived_index[k] == index) {{
            changed.derived &= ~(1u << (uint32_t)k); /* set itself: pinned */
        }}
    }}
    if (recompute != 0u) {{
        {prefix}_derive(&changed, derived);
        for (k = 0; k < {PREFIX}_N_DERIVED; ++k) {{
            if ((recompute & (1u << (uint32_t)k)) != 0u) {{
                if (!isfinite(derived[k])) {{
                    return {PREFIX}_SET_NOT_FINITE;
                }}
                if (!param_in_domain(derived_index[k], derived[k])) {{
                    return {PREFIX}_SET_OUT_OF_RANGE;
                }}
                *{prefix}_param_field(&changed, derived_index[k]) = derived[k];
            }}
        }}
    }}
    /* Record the field set and the derived parameters recomputed (only these: a field
     * written directly before stays unrecorded, and init refuses it). */
    for (j = 0; j < N_RECORD; ++j) {{
        const int field = record_index[j];
        bool derived_here = false;
        for (k = 0; k < {PREFIX}_N_DERIVED; ++k) {{
            const bool source_recomputed = (recompute & (1u << (uint32_t)k)) != 0u;
            derived_here = derived_here || ((derived_index[k] == field) && source_recomputed);
        }}
        if (field == index || derived_here) {{
            changed.record[j] = *{prefix}_param_field(&changed, field);
        }}
    }}
    if (!relations_hold(&changed)) {{
        return {PREFIX}_SET_OUT_OF_RANGE;
    }}
    *params = changed;
    return {PREFIX}_SET_OK;
}}"""


def _runtime_check(prefix: str, record: dict[str, int]) -> str:
    """Init's check, one test per record entry: a derived parameter that follows its sources,
    a source of one, or a mass-centre input that differs from the record was written directly
    (it, or the parameters derived from it, would be stale): ``-(1 + field index)``."""
    lines = []
    for j, (name, mask) in enumerate(record.items()):
        lines.append(
            f"    if (((params->derived | FIXED_BIT) & {mask}u) != 0u\n"
            f"        && params->{name} != params->record[{j}]) {{\n"
            f"        return -{1 + PARAMETERS.index(name)};\n    }}"
        )
    return "\n".join(lines)
