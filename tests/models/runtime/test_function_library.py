"""Stored Functions as compiled C (models/runtime/function_library.py) and the code digest.

The C gives CasADi's virtual machine's numbers to the bit (the derived parameters
enter every estimate); the libraries and records are real files in a private
build folder (``build_folder`` pointed at ``tmp_path``), built with gcc.
"""

import shutil

import casadi as ca
import numpy as np
import pytest

from wheelload.estimators.logs.checks import response_jacobians_function
from wheelload.models import (
    GATES,
    INPUTS,
    ModelParameters,
    equilibrium_function,
    example_vehicle_path,
    gates_function,
    load_vehicle,
    suspension_function,
)
from wheelload.models.parameters import _build_derived_function
from wheelload.models.runtime import function_cache, function_library
from wheelload.models.runtime.function_cache import PACKAGE_ROOT, SOURCE_FOLDERS, code_digest


@pytest.fixture
def private_folder(tmp_path, monkeypatch):
    """Records, stored Functions and libraries built anew in ``tmp_path``."""
    for module in (function_cache, function_library):
        monkeypatch.setattr(module, "build_folder", lambda: tmp_path)
    from wheelload.models.runtime import build_folder

    monkeypatch.setattr(build_folder, "build_folder", lambda: tmp_path)
    function_cache.stored_function.cache_clear()
    function_library.compiled_function.cache_clear()
    yield tmp_path
    function_cache.stored_function.cache_clear()
    function_library.compiled_function.cache_clear()


def _p() -> np.ndarray:
    return ModelParameters.from_vehicle(load_vehicle(example_vehicle_path())).vector()


@pytest.mark.parametrize(
    "builder",
    [suspension_function, equilibrium_function, gates_function, response_jacobians_function],
)
def test_compiled_map_equals_casadi_to_the_bit(builder, private_folder):
    rng = np.random.default_rng(3)
    n = 50
    u = rng.normal(0.0, 2.0, (len(INPUTS), n))
    inputs = {"u": u, "u_valid": (rng.random((len(INPUTS), n)) > 0.2).astype(float),
              "gates": rng.random((len(GATES), n)).round(), "p": _p()}  # fmt: skip
    function = builder()
    args = [inputs[name] for name in function.name_in()]
    expected = [np.asarray(ca.densify(out)) for out in function.map(n).call(args)]
    compiled = function_library.compiled_function(builder)
    got = compiled.map(*args)
    assert len(got) == len(expected)
    for a, b in zip(got, expected, strict=True):
        np.testing.assert_array_equal(a, b)  # to the bit: the same operations in C
    one = compiled(*[a[:, :1] if a.ndim == 2 else a for a in args])
    for a, b in zip(one, expected, strict=True):
        np.testing.assert_array_equal(a, b[:, : a.shape[1]])


def test_derived_parameters_in_c_equal_casadi(private_folder):
    p = _p()
    expected = np.asarray(_build_derived_function()(p))
    (got,) = function_library.compiled_function(_build_derived_function)(p)
    np.testing.assert_array_equal(got, expected)


def test_a_second_process_reads_the_records_and_a_damaged_record_is_made_again(private_folder):
    first = function_library.compiled_function(gates_function)
    (record,) = private_folder.glob("*gates_function*.signature.json")
    libraries = sorted(private_folder.glob("gates_function_map_*.so"))
    assert len(libraries) == 1
    function_library.compiled_function.cache_clear()
    again = function_library.compiled_function(gates_function)  # read, not built
    assert again.signature == first.signature
    assert sorted(private_folder.glob("gates_function_map_*.so")) == libraries
    record.write_text('{"name": "model_gates"')  # truncated
    function_library.compiled_function.cache_clear()
    rebuilt = function_library.compiled_function(gates_function)
    assert rebuilt.signature == first.signature
    wrong = first.signature.to_json().replace(
        f'"nnz_out": [{first.signature.nnz_out[0]}', '"nnz_out": [99'
    )
    record.write_text(wrong)  # valid JSON, the wrong sizes
    function_library.compiled_function.cache_clear()
    checked = function_library.compiled_function(gates_function)  # a library for 99 is refused
    assert checked.signature == first.signature
    assert record.read_text() == first.signature.to_json()


def _copy_sources(root, target):
    for folder in SOURCE_FOLDERS:
        shutil.copytree(root / folder, target / folder)


def test_the_digest_changes_with_any_model_or_estimator_source(tmp_path):
    _copy_sources(PACKAGE_ROOT, tmp_path)
    digest = code_digest.__wrapped__
    same = digest(tmp_path)
    assert same == code_digest()  # the copy hashes as the package itself
    for edited in ("models/equilibrium.py", "estimators/kf/step.py"):
        path = tmp_path / edited
        original = path.read_text()
        path.write_text(original + "\n# an edit\n")
        assert digest(tmp_path) != same
        path.write_text(original)
        assert digest(tmp_path) == same
    (tmp_path / "estimators" / "new_module.py").write_text("X = 1\n")
    assert digest(tmp_path) != same
