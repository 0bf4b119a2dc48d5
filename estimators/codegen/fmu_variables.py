"""The FMU's variables and its ``modelDescription.xml`` / ``buildDescription.xml`` (FMI 3.0).

Every variable is derived from the project's own declarations, in this order of value
references (the C wrapper's table and the XML are written from the same list, so they
cannot disagree):

- ``time`` (the independent variable);
- the inputs: the KF's input channels (:data:`~wheelload.models.INPUTS`) but the body-rate
  derivatives, which the FMU estimates from the rates with the library's rate filter as the
  example program does, then the tyre step's wheel channels
  (:data:`~wheelload.estimators.family.tyres.step.WHEEL_INPUTS`); start ``NaN``, a missing
  sample until the importer sets it (the library skips the updates it feeds);
- the outputs: F_z, F_x, F_y per wheel and their σ, the status bits
  (:class:`~wheelload.estimators.result.StepFlag`) and the isolated fault channels;
- the parameters: the fields of the run-time parameter struct
  (:data:`~wheelload.estimators.codegen.runtime_parameters.PARAMETERS`, in its order), tunable,
  set through ``PREFIX_set_param``; the fields that move the mass centre
  (:data:`~wheelload.models.parameters.MASS_CENTRE_INPUTS`), which ``PREFIX_set_param`` refuses,
  are constants.

Example
-------
>>> defaults = calibration_values(load_vehicle(example_vehicle_path()), CodegenOptions())
>>> [v.name for v in fmu_variables(defaults) if v.causality == "output"][:2]
['fz_fl', 'fz_fr']
"""

from __future__ import annotations

import enum
import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from wheelload.estimators.codegen.runtime_parameters import PARAMETERS
from wheelload.estimators.family.tyres.step import WHEEL_INPUTS
from wheelload.estimators.types import RATE_DERIVATIVES, SPIN, STEER, TORQUE
from wheelload.models import INPUTS, WHEELS
from wheelload.models.inputs import input_description
from wheelload.models.parameters import MASS_CENTRE_INPUTS


class Kind(enum.IntEnum):
    """What a value reference addresses in the C wrapper (``FMU_KIND_<name>``)."""

    TIME = 0
    INPUT = 1  # field ``index`` of PREFIX_input (PREFIX_input_field)
    WHEEL = 2  # wheel channel ``index`` of the tyre step
    OUTPUT = 3  # entry ``index`` of the FMU's output vector (:data:`OUTPUTS`)
    STATUS = 4  # the status bits
    FAULTS = 5  # the isolated fault channels
    PARAMETER = 6  # field ``index`` of PREFIX_params (PREFIX_param_field, PREFIX_set_param)


#: The FMU's real outputs, in the order of its output vector: (name prefix, meaning, unit).
OUTPUT_GROUPS = (
    ("fz", "wheel normal load", "N"),
    ("fz_std", "standard deviation of the wheel normal load", "N"),
    ("fx", "longitudinal tyre force, tyre frame", "N"),
    ("fx_std", "standard deviation of the longitudinal tyre force", "N"),
    ("fy", "lateral tyre force, tyre frame", "N"),
    ("fy_std", "standard deviation of the lateral tyre force", "N"),
)
OUTPUTS = tuple(f"{group}_{wheel}" for group, _, _ in OUTPUT_GROUPS for wheel in WHEELS)
#: Units and meanings of the tyre step's wheel channels (see PREFIX_tyre.h).
WHEEL_CHANNELS = {
    **{name: ("rad/s", "wheel spin") for name in SPIN},
    **{name: ("N.m", "drive minus brake torque at the wheel") for name in TORQUE},
    STEER: ("rad", "front road-wheel angle, > 0 to the left"),
}
#: The KF inputs the FMU takes (the rate derivatives come from its rate filter).
FMU_INPUTS = tuple(name for name in INPUTS if name not in RATE_DERIVATIVES)


@dataclass(frozen=True)
class Variable:
    """One FMU variable: its value reference is its position in :func:`fmu_variables`."""

    name: str
    kind: Kind
    index: int
    type: str  # Float64 or UInt32
    causality: str
    variability: str
    description: str
    unit: str = ""
    start: float | None = None
    initial: str | None = None


def _unit(text: str) -> str:
    """The unit in brackets of a description (``[m/s^2]`` -> ``m/s2``); '' without one."""
    found = re.search(r"\[([^\]]+)\]", text)
    return found.group(1).replace("^", "") if found else ""


def _part_unit(unit: str, part: int) -> str:
    """Part ``part``'s unit of a layout field's ``unit``: one unit per part, comma-separated,
    the last repeated for the parts after it (``N^2 s, N^2 m^2 s``: the vertical row, then
    the moment rows); none where the field's unit refers elsewhere (``see FilterTuning``)."""
    if not unit or unit.startswith("see "):
        return ""
    units = [u.strip() for u in unit.split(",")]
    return units[min(part, len(units) - 1)].replace("^", "")


def fmu_variables(defaults: dict[str, float]) -> tuple[Variable, ...]:
    """The FMU's variables in value-reference order; ``defaults``: the parameter struct's
    values by field name (the library's ``PREFIX_default_params``)."""
    variables = [Variable("time", Kind.TIME, 0, "Float64", "independent", "continuous",
                          "simulation time", "s")]  # fmt: skip
    for name in FMU_INPUTS:
        text = input_description(name)
        variables.append(Variable(name, Kind.INPUT, INPUTS.index(name), "Float64", "input",
                                  "discrete", text, _unit(text), math.nan))  # fmt: skip
    for k, name in enumerate(WHEEL_INPUTS):
        unit, text = WHEEL_CHANNELS[name]
        variables.append(Variable(name, Kind.WHEEL, k, "Float64", "input", "discrete",
                                  f"{text} [{unit}]", unit, math.nan))  # fmt: skip
    for group, text, unit in OUTPUT_GROUPS:
        for wheel in WHEELS:
            name = f"{group}_{wheel}"
            variables.append(Variable(name, Kind.OUTPUT, OUTPUTS.index(name), "Float64",
                                      "output", "discrete", f"{text} [{unit}]", unit,
                                      initial="calculated"))  # fmt: skip
    variables.append(Variable("status", Kind.STATUS, 0, "UInt32", "output", "discrete",
                              "status bits of the step (wheelload StepFlag)",
                              initial="calculated"))  # fmt: skip
    variables.append(Variable("faults", Kind.FAULTS, 0, "UInt32", "output", "discrete",
                              "bit k: fault channel k isolated and dropped",
                              initial="calculated"))  # fmt: skip
    for field in PARAMETERS.fields:
        for k, name in enumerate(field.parts):
            fixed = name in MASS_CENTRE_INPUTS
            text = field.doc or field.name
            variables.append(Variable(
                name, Kind.PARAMETER, PARAMETERS.index(name), "Float64",
                "local" if fixed else "parameter", "constant" if fixed else "tunable",
                f"{text} (fixed: moves the mass centre; regenerate from the changed vehicle "
                "file)" if fixed else text, _part_unit(field.unit, k), defaults[name],
            ))  # fmt: skip
    return tuple(variables)


def _number(value: float) -> str:
    """A start value as XML Schema ``xs:double`` text, read back exactly."""
    return "NaN" if math.isnan(value) else repr(float(value))


def model_description(
    variables: tuple[Variable, ...],
    *,
    model_identifier: str,
    token: str,
    interval: float,
    description: str,
    version: str,
) -> str:
    """``modelDescription.xml`` (FMI 3.0 co-simulation, fixed internal step ``interval``)."""
    root = ET.Element("fmiModelDescription", fmiVersion="3.0", modelName=model_identifier,
                      instantiationToken=token, description=description,
                      generationTool=f"wheelload {version}",
                      variableNamingConvention="flat")  # fmt: skip
    ET.SubElement(root, "CoSimulation", modelIdentifier=model_identifier,
                  canHandleVariableCommunicationStepSize="true",
                  fixedInternalStepSize=repr(interval),
                  canBeInstantiatedOnlyOncePerProcess="false")  # fmt: skip
    units = ET.SubElement(root, "UnitDefinitions")
    for unit in sorted({v.unit for v in variables if v.unit}):
        ET.SubElement(units, "Unit", name=unit)
    categories = ET.SubElement(root, "LogCategories")
    ET.SubElement(categories, "Category", name="logStatusError",
                  description="a refused value or call, with the reason")  # fmt: skip
    ET.SubElement(root, "DefaultExperiment", startTime="0", stepSize=repr(interval))
    model_variables = ET.SubElement(root, "ModelVariables")
    for reference, v in enumerate(variables):
        attributes = {"name": v.name, "valueReference": str(reference),
                      "description": v.description, "causality": v.causality,
                      "variability": v.variability}  # fmt: skip
        if v.initial is not None:
            attributes["initial"] = v.initial
        if v.unit:
            attributes["unit"] = v.unit
        if v.start is not None:
            attributes["start"] = _number(v.start)
        ET.SubElement(model_variables, v.type, attributes)
    structure = ET.SubElement(root, "ModelStructure")
    outputs = [k for k, v in enumerate(variables) if v.causality == "output"]
    for reference in outputs:  # computed in doStep from the inputs held before it
        ET.SubElement(structure, "Output", valueReference=str(reference), dependencies="",
                      dependenciesKind="")  # fmt: skip
    for reference in outputs:
        ET.SubElement(structure, "InitialUnknown", valueReference=str(reference))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def build_description(model_identifier: str, sources: tuple[str, ...]) -> str:
    """``sources/buildDescription.xml``: one C99 source file set, linked with libm."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    configuration = ET.SubElement(root, "BuildConfiguration", modelIdentifier=model_identifier)
    files = ET.SubElement(configuration, "SourceFileSet", language="C99")
    for name in sources:
        ET.SubElement(files, "SourceFile", name=name)
    ET.SubElement(configuration, "Library", name="m", external="true",
                  description="the C math library (libm)")  # fmt: skip
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"
