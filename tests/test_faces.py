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
