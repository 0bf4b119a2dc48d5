"""The default filter step Function kept on disk between runs (serialised CasADi).

Building :func:`~wheelload.estimators.kf.step.step_function` (the models'
expressions, Jacobians, guards, common subexpressions) takes about 0.2 s of
every ``wheelload estimate``; loading its serialised form takes about 15 ms.
The file is named by a hash of the code it is built from (every ``.py`` file
of ``wheelload.models`` and ``wheelload.estimators``) and of the CasADi
version, so an edit of any of them builds it again; it lives in the private
build folder of the compiled loops
(:func:`~wheelload.models.files.build_folder.build_folder`), written to a temporary
file and renamed into place. A file that does not load is built again (with a
one-line note).

Example
-------
>>> step = default_step_function()  # the same Function as step_function()
"""

from __future__ import annotations

import functools
import hashlib
import logging
import os
from pathlib import Path

import casadi as ca

from wheelload.estimators.kf.step import STEP_NAME, step_function
from wheelload.models.files.build_folder import build_folder
from wheelload.models.files.temporaries import temporary_file

_log = logging.getLogger(__name__)


def _code_digest() -> str:
    """Hash of the models' and estimators' source files and of the CasADi version."""
    import wheelload.estimators
    import wheelload.models

    digest = hashlib.sha256(f"casadi {ca.__version__}\n".encode())
    for package in (wheelload.models, wheelload.estimators):
        root = Path(package.__file__).parent
        for path in sorted(root.rglob("*.py")):
            digest.update(f"{path.relative_to(root.parent)}\n".encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


@functools.cache
def default_step_function() -> ca.Function:
    """:func:`~wheelload.estimators.kf.step.step_function` with its defaults, loaded from
    the build folder when this code built it before (module docstring)."""
    path = build_folder() / f"{STEP_NAME}_{_code_digest()}.casadi"
    if path.exists():
        try:
            return ca.Function.deserialize(path.read_text())
        except (RuntimeError, OSError, UnicodeDecodeError):  # truncated or corrupt
            _log.warning("wheelload: note: cached filter step %s does not load: built again", path)
    step = step_function()
    try:
        temporary = temporary_file(path.parent, path.stem, path.suffix)
    except OSError:
        return step  # not cached: the step is still returned
    try:
        temporary.write_text(step.serialize())
        os.replace(temporary, path)
    except OSError:
        pass  # not cached: the step is still returned
    finally:
        temporary.unlink(missing_ok=True)
    return step
