"""The filter step loaded from the build folder is the Function step_function() builds.

Checked to the bit: the same generated C (so the same compiled loop and fast
step) and the same outputs from CasADi's virtual machine on random inputs.
"""

import casadi as ca
import numpy as np

from wheelload.estimators.kf import step_cache
from wheelload.estimators.kf.step import step_function


def _c_source(function: ca.Function) -> str:
    generator = ca.CodeGenerator("step.c", {"with_header": False})
    generator.add(function)
    return generator.dump()


def _same(loaded: ca.Function, built: ca.Function) -> None:
    assert loaded.name() == built.name()
    assert loaded.name_in() == built.name_in() and loaded.name_out() == built.name_out()
    assert _c_source(loaded) == _c_source(built)
    rng = np.random.default_rng(7)
    args = [rng.standard_normal(built.sparsity_in(i).shape) for i in range(built.n_in())]
    for a, b in zip(loaded.call(args), built.call(args), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_cached_step_equals_the_built_one_and_a_corrupt_file_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setattr(step_cache, "build_folder", lambda: tmp_path)
    built = step_function()
    first = step_cache.default_step_function.__wrapped__()  # builds and writes the file
    (written,) = tmp_path.glob("*.casadi")
    loaded = step_cache.default_step_function.__wrapped__()  # loads it
    _same(first, built)
    _same(loaded, built)
    written.write_text("not a serialised function")
    rebuilt = step_cache.default_step_function.__wrapped__()
    _same(rebuilt, built)
    assert written.read_text() == built.serialize()
    assert list(tmp_path.glob("*.tmp")) == []
