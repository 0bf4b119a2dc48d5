"""A method's keyword options checked against its options dataclass, before it is built.

Each registered method declares its options as a frozen dataclass
(:attr:`~wheelload.estimators.protocol.MethodInfo.options`): one field a keyword,
its type and default. :func:`check_options` refuses a name the dataclass does not
have, or a value not of the field's type, with one line naming the option, the
method and the valid options.

Example
-------
>>> check_options(method("kf"), {"static": loads})  # passes
>>> check_options(method("kf"), {"horizon": 3})  # UnknownOptionError
"""

from __future__ import annotations

import dataclasses
import numbers
import sys
import types
import typing
from collections.abc import Callable
from typing import Any

import numpy as np

from wheelload.estimators.protocol import MethodInfo


class UnknownOptionError(TypeError):
    """An option passed to ``build`` that the method does not take, or of the wrong type."""


def valid_options(info: MethodInfo) -> tuple[str, ...]:
    """The keyword options of method ``info``, in its options dataclass's order."""
    return tuple(field.name for field in dataclasses.fields(info.options))


def check_options(info: MethodInfo, options: dict[str, Any]) -> None:
    """Raise :class:`UnknownOptionError` for an option ``info``'s options dataclass does not
    declare, or whose value is not of the declared type."""
    names = valid_options(info)
    listed = ", ".join(names) or "none"
    for key, value in options.items():
        if key not in names:
            raise UnknownOptionError(
                f"method {info.name!r} takes no option {key!r}; valid options: {listed}"
            )
        hint = field_type(info.options, key)
        if not accepts(value, hint):
            raise UnknownOptionError(
                f"method {info.name!r}: option {key!r} must be {type_name(hint)}, got "
                f"{type(value).__name__}; valid options: {listed}"
            )


def field_type(options: type, name: str) -> Any:
    """The annotated type of field ``name`` of the options dataclass, evaluated alone (the
    other fields' annotations, which may name a slow module's types, are left unread)."""
    for cls in options.__mro__:
        annotation = cls.__dict__.get("__annotations__", {}).get(name)
        if annotation is not None:
            if not isinstance(annotation, str):
                return annotation
            namespace = vars(sys.modules[cls.__module__])
            return eval(annotation, namespace)  # noqa: S307 (the module's own annotation)
    raise KeyError(name)


def accepts(value: Any, hint: Any) -> bool:
    """Whether ``value`` is of the annotated type ``hint`` (a class, a union, a generic)."""
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        return any(accepts(value, arg) for arg in typing.get_args(hint))
    if hint is Any:
        return True
    if hint is type(None):
        return value is None
    if hint is bool:
        return isinstance(value, bool | np.bool_)
    if hint is float:
        return isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)
    if hint is int:
        return isinstance(value, numbers.Integral) and not isinstance(value, bool | np.bool_)
    if origin is not None:
        return callable(value) if origin is Callable else isinstance(value, origin)
    return isinstance(value, hint)


def type_name(hint: Any) -> str:
    """``hint`` as one reads it in a message (``float``, ``GuardSettings or None``)."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        return " or ".join(type_name(arg) for arg in typing.get_args(hint))
    if hint is type(None):
        return "None"
    return getattr(hint, "__name__", str(hint))
