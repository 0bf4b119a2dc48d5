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
import textwrap

from wheelload.estimators.kernels.c_emitter import Precision, emit_statements, literal
from wheelload.estimators.kernels.layout import Field, Layout
from wheelload.estimators.kf.tuning import TUNING
from wheelload.models import ModelParameters, Vehicle
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


#: The runtime parameter struct ``PREFIX_params``, in member order: the model parameters
#: (the step's ``p``), the tuning vector (its ``tuning``, :data:`TUNING`'s declaration), the
#: initial standard deviation of reset.
PARAMETERS = Layout(
    "params",
    (
        *[
            Field(name, doc="model parameter (models.parameters)")
            for name in ModelParameters.names()
        ],
        *TUNING.fields,
        Field("initial_std", unit="N", file_key=("filter", "initial_std"), doc="reset's std"),
    ),
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
            "derivation_code": _baked_set_param(prefix),
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
        "derivation_code": code,
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
    *field = value;
    return {PREFIX}_SET_OK;
}}"""


_RUNTIME_SET_PARAM = """/* Per field: bit k if it is a source of derived parameter k; FIXED_BIT if
 * it may not be set at run time. */
#define FIXED_BIT {fixed}
static const uint32_t param_feeds[{PREFIX}_N_PARAMS] = {{{feeds}}};
/* Field index of each derived parameter and of each record entry. */
static const int derived_index[{PREFIX}_N_DERIVED] = {{{derived_index}}};
#define N_RECORD ((int)(sizeof record_index / sizeof record_index[0]))
static const int record_index[] = {{{record_index}}};

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
    if (param_feeds[index] & FIXED_BIT) {{ /* its own value only: nothing moves */
        const int same = value == *{prefix}_param_field(params, index);
        return same ? {PREFIX}_SET_OK : {PREFIX}_SET_FIXED;
    }}
    changed = *params;
    *{prefix}_param_field(&changed, index) = value;
    recompute = param_feeds[index] & changed.derived;
    for (k = 0; k < {PREFIX}_N_DERIVED; ++k) {{
        if (derived_index[k] == index) {{
            changed.derived &= ~(1u << k); /* set itself: pinned */
        }}
    }}
    if (recompute != 0u) {{
        {prefix}_derive(&changed, derived);
        for (k = 0; k < {PREFIX}_N_DERIVED; ++k) {{
            if ((recompute & (1u << k)) != 0u) {{
                if (!isfinite(derived[k])) {{
                    return {PREFIX}_SET_NOT_FINITE;
                }}
                *{prefix}_param_field(&changed, derived_index[k]) = derived[k];
            }}
        }}
    }}
    /* Record the field set and the derived parameters recomputed (only these: a field
     * written directly before stays unrecorded, and init refuses it). */
    for (j = 0; j < N_RECORD; ++j) {{
        const int field = record_index[j];
        int derived_here = 0;
        for (k = 0; k < {PREFIX}_N_DERIVED; ++k) {{
            derived_here |= derived_index[k] == field && (recompute & (1u << k)) != 0u;
        }}
        if (field == index || derived_here) {{
            changed.record[j] = *{prefix}_param_field(&changed, field);
        }}
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
