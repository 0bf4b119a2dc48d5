"""A source FMU (FMI 3.0, co-simulation) of the combined F_x, F_y, F_z step.

``wheelload codegen --fmu --out DIR`` writes ``DIR/PREFIX.fmu``: a ZIP with
``modelDescription.xml`` (:mod:`~wheelload.estimators.codegen.fmu_variables`: every variable
derived from the project's declarations) and ``sources/``: the KF library and its tyre step
as ``wheelload codegen --tyre-forces`` writes them, the FMI wrapper ``PREFIX_fmu.c``
(``templates/fmu.c``, on the library's public API) and ``buildDescription.xml``. An importer
compiles the sources with its own FMI 3.0 headers (FMPy, Simulink's FMU Import block, a HIL
tool chain); the headers are not shipped. The FMU runs at the library's fixed interval
(``fixedInternalStepSize``); its tunable parameters are the run-time parameter struct's
fields, set through ``PREFIX_set_param`` and checked as ``PREFIX_init`` checks them (the tyre
step's vehicle numbers are folded into its C and are not among them).

The FMU needs the tyre step (it is the combined step) and run-time parameters.

Example
-------
>>> fmu = generate_fmu(example_vehicle_path(), Path("out"))  # out/wheelload_kf.fmu
"""

from __future__ import annotations

import hashlib
import string
import tempfile
import zipfile
from dataclasses import dataclass, replace
from importlib import resources
from importlib.metadata import version
from pathlib import Path

from wheelload.estimators.codegen.deviations import (
    FMU_DEVIATIONS,
    LIBRARY_DEVIATIONS,
    RECORD_NAME,
    deviation_record,
)
from wheelload.estimators.codegen.fmu_variables import (
    OUTPUT_GROUPS,
    OUTPUTS,
    Kind,
    build_description,
    fmu_variables,
    model_description,
)
from wheelload.estimators.codegen.kf import (
    CodegenOptions,
    ParamMode,
    calibration_values,
    generate,
)
from wheelload.estimators.logs.output_files import atomic_write
from wheelload.models import WHEELS, load_vehicle

#: Where each output group comes from in the wrapper (C, wheel k): the KF's output
#: ``estimate`` and the tyre step's ``forces``.
C_OUTPUTS = {
    "fz": "estimate.loads", "fz_std": "estimate.std", "fx": "forces.fx",
    "fx_std": "forces.fx_std", "fy": "forces.fy", "fy_std": "forces.fy_std",
}  # fmt: skip
#: The outputs before the first sample: reset's static loads with its initial std (the
#: others 0).
C_INITIAL_OUTPUTS = {"fz": "instance->state.x[k]", "fz_std": "instance->params.initial_std"}


@dataclass(frozen=True)
class GeneratedFmu:
    """The written FMU and what it was built from."""

    path: Path  # DIR/PREFIX.fmu
    model_identifier: str
    interval: float  # s, the fixed internal step
    sources: tuple[str, ...]  # files under sources/, as compiled


def fmu_options(options: CodegenOptions | None) -> CodegenOptions:
    """The library options of an FMU: the given ones with the tyre step; refuses baked
    parameters (an FMU's parameters are the run-time struct's)."""
    options = options or CodegenOptions()
    if options.params is not ParamMode.RUNTIME:
        raise ValueError(
            "--fmu: the FMU's tunable parameters are the run-time parameter struct's: "
            "leave --params at runtime"
        )
    return replace(options, tyre_forces=True)


def generate_fmu(
    vehicle_path: str | Path,
    out_dir: str | Path,
    options: CodegenOptions | None = None,
    *,
    allow_unusual: bool = False,
    force: bool = False,
) -> GeneratedFmu:
    """Write ``out_dir/PREFIX.fmu`` for a vehicle file (an existing one only with ``force``;
    written to a temporary and renamed into place)."""
    options = fmu_options(options)
    vehicle_path = Path(vehicle_path)
    vehicle = load_vehicle(vehicle_path, allow_unusual=allow_unusual)
    prefix = options.prefix
    variables = fmu_variables(calibration_values(vehicle, options))
    with tempfile.TemporaryDirectory() as folder:
        library = generate(vehicle_path, folder, options, allow_unusual=allow_unusual)
        files = {path.name: path.read_bytes() for path in (library.header, library.source,
                                                           *library.tyre)}  # fmt: skip
        token = _token(files)
    wrapper = f"{prefix}_fmu.c"
    files[wrapper] = wrapper_source(variables, options, token, vehicle_path.name).encode()
    sources = (library.source.name, library.tyre[1].name, wrapper)
    files["buildDescription.xml"] = build_description(prefix, sources).encode()
    deviations = (*LIBRARY_DEVIATIONS, *FMU_DEVIATIONS)
    files[RECORD_NAME] = deviation_record([d.for_prefix(prefix) for d in deviations]).encode()
    description = model_description(
        variables, model_identifier=prefix, token=token, interval=options.sample_interval,
        description=f"wheelload tyre-forces: F_z, F_x, F_y per wheel with sigma and status "
        f"bits, vehicle {vehicle_path.name}, {options.precision.value} precision",
        version=version("wheelload"),
    )  # fmt: skip
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{prefix}.fmu"
    with atomic_write(path, replace=force) as temporary:
        with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("modelDescription.xml", description)
            for name, data in files.items():
                archive.writestr(f"sources/{name}", data)
    return GeneratedFmu(path, prefix, options.sample_interval, sources)


def _token(files: dict[str, bytes]) -> str:
    """The instantiation token: a hash of the library's sources (the wrapper checks it)."""
    digest = hashlib.sha256()
    for name in sorted(files):
        digest.update(name.encode() + b"\0" + files[name])
    return "{" + digest.hexdigest()[:32] + "}"


def _offset(first: int) -> str:
    """``first + `` before an index, nothing for 0 (no ``0 + k``: MISRA C:2012 rule 2.2)."""
    return f"{first} + " if first else ""


def wrapper_source(variables, options: CodegenOptions, token: str, vehicle_name: str) -> str:
    """``PREFIX_fmu.c`` from ``templates/fmu.c``: the value-reference table of ``variables``."""
    rows = [f"    {{FMU_KIND_{v.kind.name}, {v.index}}}, /* {k}: {v.name} */"
            for k, v in enumerate(variables)]  # fmt: skip
    template = resources.files("wheelload.estimators.codegen") / "templates" / "fmu.c"
    first = {group: OUTPUTS.index(f"{group}_{WHEELS[0]}") for group, _, _ in OUTPUT_GROUPS}
    return string.Template(template.read_text("utf-8")).substitute(
        prefix=options.prefix,
        PREFIX=options.prefix.upper(),
        wheelload_version=version("wheelload"),
        vehicle_name=vehicle_name,
        token=token,
        interval=repr(float(options.sample_interval)),
        n_variables=str(len(variables)),
        n_outputs=str(len(OUTPUTS)),
        kind_defines="\n".join(f"#define FMU_KIND_{kind.name} {kind.value}u" for kind in Kind),
        variable_table="\n".join(rows),
        output_copy="\n".join(
            f"        instance->outputs[{_offset(first[group])}k] = (double){source}[k];"
            for group, source in C_OUTPUTS.items()
        ),
        initial_copy="\n".join(
            f"        instance->outputs[{_offset(first[group])}k] = (double){source};"
            for group, source in C_INITIAL_OUTPUTS.items()
        ),
    )
