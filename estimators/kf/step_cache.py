"""The default filter step Function kept on disk between runs (serialised CasADi).

Building :func:`~wheelload.estimators.kf.step.step_function` (the models'
expressions, Jacobians, guards, common subexpressions) takes about 0.2 s of
every ``wheelload estimate``; loading its serialised form takes about 10 ms.
It is stored as any model Function
(:func:`~wheelload.models.files.function_cache.stored_function`: named by a hash
of every ``.py`` file of ``wheelload.models`` and ``wheelload.estimators`` and of
the CasADi version, so an edit of any of them builds it again).

Example
-------
>>> step = default_step_function()  # the same Function as step_function()
"""

from __future__ import annotations

import casadi as ca

from wheelload.estimators.kf.step import step_function
from wheelload.models.files.function_cache import stored_function


def default_step_function() -> ca.Function:
    """:func:`~wheelload.estimators.kf.step.step_function` with its defaults, loaded from
    the build folder when this code built it before (module docstring)."""
    return stored_function(step_function)
