"""A C function of a small kernel source, compiled once and loaded (one for each kernel).

The build is :func:`wheelload.models.runtime.build_folder.cached_library`'s: named by the hash
of the source and the compiler command, checked against its record before it is loaded.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable

from wheelload.models.runtime.build_folder import COMPILER, cached_library


def c_function(source: str, name: str, purpose: str, argtypes: list) -> Callable[..., None]:
    """The function ``name`` (returning void) of ``source``; ``purpose`` completes
    "gcc is needed to ..."."""
    library = cached_library(source, name, COMPILER, lambda path: ctypes.CDLL(str(path)), purpose)
    function = getattr(library, name)
    function.restype = None
    function.argtypes = argtypes
    return function
