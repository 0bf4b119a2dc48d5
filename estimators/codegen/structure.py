"""The model structure of a generated library: what its C depends on besides the values.

With run-time parameters (:attr:`~wheelload.estimators.codegen.kf.ParamMode.RUNTIME`) every
number of the vehicle file reaches the generated step through the parameter struct, set
before a run; the code itself follows from the generator's other inputs. Their key,
:func:`structure_key`, names the record of a compiled library instead of the file's text,
so that a comment, +1 kg or a new spring rate reuses the library and only a change of
structure generates it again (and compiles it, when its text is new). It hashes, each in full:

- the generator's code: the ``.py`` files it is made of
  (:func:`~wheelload.models.runtime.function_cache.code_digest`) and its C templates;
- the step Function the C is emitted from (serialised: the model terms and the sizes);
- the :class:`~wheelload.estimators.codegen.kf.CodegenOptions` (precision, prefix, sample
  interval, forms), every field by its ``repr``;
- the vehicle's shape (:func:`vehicle_shape`): the parsed vehicle with each number replaced
  by the word ``number`` and each text by ``text`` (the project states options as enums and
  switches, never as strings), its switches, enums, absent sections and list lengths kept.

A switch of the file (a model term, the payload filter) changes the key; a number or a
text does not. The shape is walked from the :class:`~wheelload.models.Vehicle` dataclasses
themselves, so a new section or switch is part of it without an edit here.

Example
-------
>>> key = structure_key(step, load_vehicle("car.toml"), CodegenOptions(prefix="wheelload_batch"))
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import hashlib
from importlib import resources

import casadi as ca

from wheelload.models import Vehicle
from wheelload.models.runtime.function_cache import code_digest


def vehicle_shape(value: object) -> object:
    """``value`` (a vehicle or any part of it) with its numbers and texts replaced by their
    kind: a nested tuple of field names, switches, enums, ``None`` and kinds."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = dataclasses.fields(value)
        return type(value).__name__, tuple(
            (f.name, vehicle_shape(getattr(value, f.name))) for f in fields
        )
    if value is None or isinstance(value, (bool, enum.Enum)):
        return value
    if isinstance(value, (int, float)):
        return "number"
    if isinstance(value, str):
        return "text"
    if isinstance(value, (tuple, list)):
        return tuple(vehicle_shape(item) for item in value)
    if isinstance(value, dict):
        return tuple(sorted((str(k), repr(vehicle_shape(v))) for k, v in value.items()))
    return repr(value)  # anything else: kept whole (a change builds again)


@functools.cache
def templates_digest() -> str:
    """Hash of the C templates the generator fills (``estimators/codegen/templates``)."""
    digest = hashlib.sha256()
    folder = resources.files("wheelload.estimators.codegen") / "templates"
    for entry in sorted(folder.iterdir(), key=lambda item: item.name):
        if entry.is_file():
            digest.update(f"{entry.name}\n".encode())
            digest.update(entry.read_bytes())
    return digest.hexdigest()


def structure_key(step: ca.Function, vehicle: Vehicle, options: object) -> str:
    """Hash of everything the generated library's code depends on but the vehicle's values
    (module docstring): two vehicles of one key share a compiled library."""
    digest = hashlib.sha256()
    for part in (
        code_digest(),
        templates_digest(),
        step.serialize(),
        repr(options),
        repr(vehicle_shape(vehicle)),
    ):
        digest.update(part.encode())
        digest.update(b"\0")
    return digest.hexdigest()
