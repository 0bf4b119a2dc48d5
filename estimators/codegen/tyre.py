"""Generate the tyre-force step (``tyre-forces``) as C beside the two-stage KF's library.

With ``CodegenOptions(tyre_forces=True)`` (``wheelload codegen --tyre-forces``) the
library gets ``PREFIX_tyre.h`` / ``PREFIX_tyre.c``: ``PREFIX_tyre_step`` takes the KF's
input and output of a sample and the wheel channels (spins, torques, steer) and gives
:math:`F_x, F_y` per wheel with σ, so that the KF step and it make the combined step of
the ``tyre-forces`` method (:math:`F_z` from the KF). The C is emitted from the Function
the Python method runs (:func:`~wheelload.estimators.family.tyres.step.tyre_core_function`,
composed with the force sums of :meth:`TyreForces.force_sum_function
<wheelload.estimators.family.tyres.forces.TyreForces.force_sum_function>`), with the
vehicle's numbers and the settings folded in; the spin observers are discretised at the
library's sample interval (``--interval``) and the C refuses a step at another dt
(``interval_refused``, counted) rather than give forces of the wrong discretisation.
The example program then reads ``omega_*``, ``torque_*`` and
``steer`` and writes ``fx_*``, ``fy_*`` and their σ beside the loads.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from wheelload.estimators.family.tyres.forces import TyreForces
from wheelload.estimators.family.tyres.step import CORE, WHEEL_INPUTS
from wheelload.estimators.kernels.c_emitter import Precision, emit_statements, flop_count, literal
from wheelload.models import INPUTS, WHEELS, Vehicle

#: Inputs and outputs of the C tyre kernel, in order.
TYRE_KERNEL_INPUTS = ("core", "wheels", "wheels_valid", "u", "u_valid", "loads",
                      "mass_properties", "dt")  # fmt: skip
TYRE_KERNEL_OUTPUTS = ("core_next", "fx", "fx_std", "fy", "fy_std", "high_slip")
#: Kernel inputs that hold exactly 0 or 1.
TYRE_BOOLEAN_INPUTS = (2, 4)


def tyre_kernel_function(vehicle: Vehicle, sample_interval: float) -> ca.Function:
    """``tyre_kernel(core, wheels, wheels_valid, u, u_valid, loads, mass_properties, dt)``:
    the force sums from the KF's input ``u`` (:data:`~wheelload.models.INPUTS` order, 0
    where missing) and its online mass properties, then the observers' core step,
    discretised at ``sample_interval``.

    A force sum is valid where every input it depends on is (the acceleration components
    it reads, and the speed for the drag), as NaN would propagate in Python.
    """
    method = TyreForces(vehicle)
    core = ca.SX.sym("core", CORE.size)
    wheels = ca.SX.sym("wheels", len(WHEEL_INPUTS))
    wheels_valid = ca.SX.sym("wheels_valid", len(WHEEL_INPUTS))
    u, u_valid = ca.SX.sym("u", len(INPUTS)), ca.SX.sym("u_valid", len(INPUTS))
    loads, dt = ca.SX.sym("loads", 4), ca.SX.sym("dt")
    loaded = ca.SX.sym("mass_properties", 4)

    def channel(name: str):
        return u[INPUTS.index(name)], u_valid[INPUTS.index(name)]

    d = ca.vertcat(*[channel(f"d_{wheel}")[0] for wheel in WHEELS])
    acc = ca.vertcat(*[channel(axis)[0] for axis in ("ax", "ay", "az")])
    (vx, vx_valid), (rate, rate_valid) = channel("vx"), channel("wz")
    sums = method.force_sum_function(d, acc, vx, rate, loaded)
    sums_valid = []
    for row in range(2):
        valid = 1
        for name, value in (("ax", acc[0]), ("ay", acc[1]), ("az", acc[2]), ("vx", vx)):
            if ca.depends_on(sums[row], value):
                valid = valid * channel(name)[1]
        sums_valid.append(valid)
    observer = ca.DM(method.observer_input(sample_interval))
    outputs = method.core_function(core, wheels, wheels_valid, sums, ca.vertcat(*sums_valid),
                                   rate, rate_valid, vx, vx_valid, loads, loaded, dt,
                                   observer)  # fmt: skip
    return ca.Function(
        "tyre_kernel",
        [core, wheels, wheels_valid, u, u_valid, loads, loaded, dt],
        list(outputs),
        list(TYRE_KERNEL_INPUTS),
        list(TYRE_KERNEL_OUTPUTS),
    )


def interval_tolerance(sample_interval: float, precision: Precision) -> float:
    """Largest difference of a step's dt from ``sample_interval`` the C tyre step takes [s]:
    half a nanosecond in double (the Python step discretises at dt rounded to 1 ns, so the
    same observer), 16 float roundings of the interval in float."""
    if precision is Precision.DOUBLE:
        return 0.5e-9
    return float(16 * np.spacing(np.float32(sample_interval)))


def tyre_substitutions(
    vehicle: Vehicle, sample_interval: float, precision: Precision, prefix: str
) -> dict[str, str]:
    """Template fields of ``tyre.h`` / ``tyre.c`` and of the example's tyre part."""
    kernel = tyre_kernel_function(vehicle, sample_interval)
    real = f"{prefix}_real"
    body = emit_statements(
        kernel,
        ["core[{}]", "wheels[{}]", "wheels_valid[{}]", "u[{}]", "u_valid[{}]", "loads[{}]",
         "mass_properties[{}]", "dt"],
        [f"{name}[{{}}]" for name in TYRE_KERNEL_OUTPUTS],
        precision,
        real,
        boolean_inputs=TYRE_BOOLEAN_INPUTS,
    )  # fmt: skip
    return {
        "tyre_flops": str(flop_count(kernel)),
        "tyre_kernel_body": "\n".join(f"    {line}" for line in body.splitlines()),
        "n_core": str(CORE.size),
        "n_wheel": str(len(WHEEL_INPUTS)),
        "wheel_names": "\n".join(f'    "{name}",' for name in WHEEL_INPUTS),
        "last_fx": str(CORE.last_fx.start),
        "tyre_interval_tolerance": literal(
            interval_tolerance(sample_interval, precision), precision
        ),
    }
