"""Where generated code is compiled: a private folder of the current user.

Compiled libraries are cached by the hash of their source and loaded
without further checks, so the folder must be writable by this user alone:
``<system temp>/wheelload-build-<uid>``, mode 0700, owned by the user, not
a symbolic link. Anything else is refused rather than trusted.
"""

from __future__ import annotations

import hashlib
import os
import stat
import subprocess
import tempfile
from pathlib import Path


def build_folder() -> Path:
    """The private build folder, created on first use."""
    folder = Path(tempfile.gettempdir()) / f"wheelload-build-{os.getuid()}"
    folder.mkdir(mode=0o700, exist_ok=True)
    info = folder.lstat()
    if (
        not stat.S_ISDIR(info.st_mode)
        or info.st_uid != os.getuid()
        or stat.S_IMODE(info.st_mode) & 0o077
    ):
        raise RuntimeError(
            f"{folder} is not a folder private to this user (owner {info.st_uid}, mode "
            f"{stat.S_IMODE(info.st_mode):o}); remove it so that it can be made again"
        )
    return folder


def jit_options() -> dict:
    """CasADi JIT with the system C compiler, building in :func:`build_folder`."""
    return {
        "jit": True,
        "compiler": "shell",
        "jit_options": {"flags": ["-O2"], "directory": f"{build_folder()}{os.sep}"},
    }


#: Flags of the plant's compiled chunk (as the CasADi JIT it replaces: ``-O2``).
CHUNK_FLAGS = ("-O2", "-fPIC", "-shared")


def cached_library(source: str, name: str, command: tuple[str, ...], load, purpose: str):
    """``source`` compiled once by ``command`` (gcc and its flags) and loaded with ``load``.

    The library is named by the hash of the source and the command, built
    under :func:`build_folder` through a temporary file renamed into place; a
    cached library that does not load (truncated, empty, corrupt) is removed
    and built again. ``purpose`` completes "gcc is needed to ...".
    """
    digest = hashlib.sha256((" ".join(command) + "\n" + source).encode()).hexdigest()[:16]
    folder = build_folder()
    library = folder / f"{name}_{digest}.so"
    if library.exists():
        try:
            return load(library)
        except (OSError, RuntimeError):
            library.unlink(missing_ok=True)
    handle, c_name = tempfile.mkstemp(suffix=".c", prefix=f"{name}_", dir=folder)
    c_file = Path(c_name)
    with os.fdopen(handle, "w") as stream:
        stream.write(source)
    partial = c_file.with_suffix(".so.tmp")
    try:
        subprocess.run(
            [*command, "-o", str(partial), str(c_file), "-lm"],
            check=True,
            capture_output=True,
            text=True,
        )
    except FileNotFoundError:
        raise RuntimeError(f"no C compiler 'gcc' found: it is needed to {purpose}") from None
    except subprocess.CalledProcessError as error:
        raise RuntimeError(f"compiling {name} failed:\n{error.stderr}") from None
    finally:
        c_file.unlink(missing_ok=True)
    partial.replace(library)
    return load(library)


def cached_function(function):
    """``function`` as generated C, compiled once per source and loaded (``casadi.external``).

    The library is named by the hash of its C source and flags (which hold
    every parameter baked into the expressions), so a second process with the
    same model loads it instead of compiling again (the CasADi JIT compiles on
    every call); see :func:`cached_library`.
    """
    import casadi as ca

    name = function.name()
    generator = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    generator.add(function)
    return cached_library(
        generator.dump(),
        name,
        ("gcc", *CHUNK_FLAGS),
        lambda library: ca.external(name, str(library)),
        "compile the plant",
    )
