"""Modules the command line imports on first use: a stand-in until an attribute is read.

``import casadi as ca`` opens most modules of ``wheelload.models`` and
``wheelload.estimators`` (the symbolic models are built with it) and costs about
30 ms of CPU; a warm single-log estimate reads the stored model functions and the
filter loop as compiled C (:mod:`wheelload.models.runtime.function_library`) and never
calls CasADi. :func:`defer` puts a stand-in into ``sys.modules`` that imports the
module at the first read of one of its attributes (``ca.SX``, ``ca.Function``) and
from then on carries the module's names; a command that builds a model still gets
CasADi, a moment later.

Example
-------
>>> defer("casadi")
>>> import casadi as ca  # nothing imported yet
>>> ca.SX  # imports casadi
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
import types


class _Deferred(types.ModuleType):
    """The stand-in: its first missing attribute imports the module (:func:`defer`)."""

    def __getattr__(self, attribute: str):
        return getattr(_load(self), attribute)


def _load(standin: _Deferred) -> types.ModuleType:
    """The module itself, imported in place of ``standin``, whose names it then carries."""
    name = standin.__name__
    if sys.modules.get(name) is standin:
        del sys.modules[name]
    module = importlib.import_module(name)
    standin.__dict__.update(module.__dict__)
    return module


def defer(name: str) -> None:
    """Import the top-level module ``name`` on first use (module docstring); nothing when it
    is imported already or cannot be found (its import then fails where it is written)."""
    if name in sys.modules:
        return
    spec = importlib.util.find_spec(name)
    if spec is None:
        return
    standin = _Deferred(name)
    standin.__spec__ = spec  # what ``import name`` reads of a module already in sys.modules
    standin.__path__ = spec.submodule_search_locations or []
    sys.modules[name] = standin


def loaded(name: str) -> bool:
    """Whether module ``name`` is imported, not only deferred."""
    return name in sys.modules and not isinstance(sys.modules[name], _Deferred)
