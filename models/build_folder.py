"""Where generated code is compiled: a private folder of the current user.

Compiled libraries are cached by the hash of their source and loaded
without further checks, so the folder must be writable by this user alone:
``<system temp>/wheelload-build-<uid>``, mode 0700, owned by the user, not
a symbolic link. Anything else is refused rather than trusted.
"""

from __future__ import annotations

import os
import stat
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
