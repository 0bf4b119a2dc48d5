"""wheelload: the four wheel normal loads of a road vehicle from suspension travel and an IMU.

The main names, each imported on first use (a command pays only for what it runs)::

    import wheelload

    vehicle = wheelload.load_vehicle(wheelload.example_vehicle_path())
    estimate = wheelload.build("kf", vehicle).run(wheelload.read_log("drive.parquet"))

The full contract is :mod:`wheelload.estimators` (methods, options, results, log I/O) and
:mod:`wheelload.models` (the vehicle file); ``wheelload.__version__`` is the installed
distribution's version.
"""

import importlib

#: The main names, by the face that holds them (imported when first asked for: this module
#: imports nothing of the package, so ``wheelload --version`` stays light).
_FACES = {
    "wheelload.estimators": (
        "Estimate",
        "Estimator",
        "MethodInfo",
        "Signals",
        "build",
        "method",
        "methods",
        "read_log",
        "write_log",
    ),
    "wheelload.models": ("Vehicle", "example_vehicle_path", "load_vehicle"),
}
_FACE_OF = {name: face for face, names in _FACES.items() for name in names}

__all__ = ["__version__", *sorted(_FACE_OF)]


def __getattr__(name: str) -> object:
    """``__version__`` from the installed distribution's metadata, or a main name."""
    if name == "__version__":
        from importlib import metadata

        try:
            value = metadata.version("wheelload")
        except metadata.PackageNotFoundError:  # a source tree on the path, not installed
            value = "0+unknown"
    elif name in _FACE_OF:
        value = getattr(importlib.import_module(_FACE_OF[name]), name)
    else:
        raise AttributeError(f"module 'wheelload' has no attribute '{name}'")
    globals()[name] = value  # found directly from now on
    return value


def __dir__() -> list[str]:
    own = {name for name in globals() if name.startswith("__") or not name.startswith("_")}
    return sorted((own - {"importlib"}) | set(__all__))
