"""The plant's compiled chunk is built once per model and loaded from the private build folder."""

import casadi as ca
import numpy as np

from wheelload.models.plant.dynamics import chunk_from_ode
from wheelload.models.runtime.build_folder import build_folder


def _ode(stiffness: float) -> ca.Function:
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u")
    xdot = ca.vertcat(x[1], -stiffness * x[0] - 0.4 * x[1] + u)
    return ca.Function("spring_ode", [x, u], [xdot, x[0] * stiffness], ["x", "u"], ["xdot", "y"])


def _libraries():
    return {p: p.stat().st_mtime_ns for p in build_folder().glob("spring_chunk_*.so")}


def test_the_chunk_is_compiled_once_and_equals_the_casadi_vm():
    stiffness = 7.0 + np.random.default_rng().random()  # a model no earlier run has built
    before = _libraries()
    compiled = chunk_from_ode(_ode(stiffness), 1000.0, 20, "spring_chunk")
    built = _libraries()
    (library,) = set(built) - set(before)
    again = chunk_from_ode(_ode(stiffness), 1000.0, 20, "spring_chunk")
    assert _libraries() == built  # loaded, not compiled again
    reference = chunk_from_ode(_ode(stiffness), 1000.0, 20, "spring_chunk", jit=False)
    x = np.array([0.01, 0.0])
    for _ in range(5):
        a, ya = compiled(x, 0.5)
        b, yb = again(x, 0.5)
        c, yc = reference(x, 0.5)
        assert np.array_equal(np.asarray(a), np.asarray(b))
        # Same IEEE operations in C and in the VM: equal to rounding (1e-12 relative).
        np.testing.assert_allclose(np.asarray(a), np.asarray(c), rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(float(ya), float(yc), rtol=1e-12)
        x = np.asarray(a).ravel()
    damaged = library.with_suffix(".damaged")  # a damaged cache entry is built again
    damaged.write_bytes(b"not a library")
    damaged.replace(library)  # a new file: the loaded library's pages stay valid
    rebuilt = chunk_from_ode(_ode(stiffness), 1000.0, 20, "spring_chunk")
    assert np.array_equal(np.asarray(rebuilt(x, 0.5)[0]), np.asarray(compiled(x, 0.5)[0]))
    library.unlink()
