"""The faces' names: ``dir()`` of ``wheelload.estimators`` and ``wheelload.models`` shows their
public names (each imported on first use), not the lazy loader's."""

import wheelload.estimators
import wheelload.models


def test_dir_of_a_face_shows_its_public_names():
    shown = dir(wheelload.estimators)
    assert set(wheelload.estimators.__all__) <= set(shown)
    assert {"build", "method", "methods", "Estimator", "MethodInfo", "KfOptions"} <= set(shown)
    assert "lazy_names" not in shown
    assert set(wheelload.models.__all__) <= set(dir(wheelload.models))


def test_the_log_scans_parts_are_found_but_are_not_the_face():
    """``LogScan`` and ``ThinnedInputs`` (the one-read estimate's parts) are internals: found
    through the door for the studies, never listed by ``__all__`` or ``dir()``."""
    from wheelload.estimators.kf import log_stream

    for name in ("LogScan", "ThinnedInputs"):
        assert getattr(wheelload.estimators, name) is getattr(log_stream, name)
        assert name not in wheelload.estimators.__all__
        assert name not in dir(wheelload.estimators)  # also once imported
    assert {"LogStream", "scan_log"} <= set(wheelload.estimators.__all__)
