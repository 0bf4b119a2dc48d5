"""The filter step loaded from the build folder is the Function step_function() builds.

Checked to the bit: the same generated C (so the same compiled loop and fast
step) and the same outputs from CasADi's virtual machine on random inputs.
"""

import casadi as ca
import numpy as np

from wheelload.estimators.kf.step import step_function
from wheelload.models.runtime import function_cache


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
    monkeypatch.setattr(function_cache, "build_folder", lambda: tmp_path)
    load = function_cache.stored_function.__wrapped__  # without the one-process memo
    built = step_function()
    first = load(step_function)  # builds and writes the file
    (written,) = tmp_path.glob("*.casadi")
    loaded = load(step_function)  # loads it
    _same(first, built)
    _same(loaded, built)
    written.write_text("not a serialised function")
    rebuilt = load(step_function)
    _same(rebuilt, built)
    assert written.read_text() == built.serialize()
    assert list(tmp_path.glob("*.tmp")) == []
