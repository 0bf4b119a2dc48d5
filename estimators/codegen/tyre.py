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

import dataclasses
from types import SimpleNamespace

import casadi as ca
import numpy as np

from wheelload.estimators.codegen.runtime_parameters import domain_function
from wheelload.estimators.family.tyres.forces import HIGH_SLIP_Q, HIGH_SLIP_R, TyreForces
from wheelload.estimators.family.tyres.step import CORE, WHEEL_INPUTS, tyre_core_function
from wheelload.estimators.kernels.c_emitter import Precision, emit_statements, flop_count, literal
from wheelload.estimators.kernels.layout import Domain, Field, Layout
from wheelload.models import INPUTS, WHEELS, Vehicle
from wheelload.models.vehicle.wheel_geometry import wheel_centres

#: Inputs and outputs of the C tyre kernel, in order.
TYRE_KERNEL_INPUTS = ("core", "wheels", "wheels_valid", "u", "u_valid", "loads",
                      "mass_properties", "dt", "params")  # fmt: skip
TYRE_KERNEL_OUTPUTS = ("core_next", "fx", "fx_std", "fy", "fy_std", "high_slip")
#: Kernel inputs that hold exactly 0 or 1.
TYRE_BOOLEAN_INPUTS = (2, 4)


#: The tyre step's run-time parameters (``PREFIX_tyre_params``), each a number of
#: :class:`~wheelload.estimators.family.tyres.forces.Constants` with its domain; the
#: tyres' split numbers only for a vehicle with a ``[cornering]`` section. The wheel
#: centres follow lf, lr and the tracks at run time (wheel_centres, in the step); the yaw
#: inertia is its own number.
_SETTABLE = (
    Field("rolling", doc="rolling-resistance coefficient", domain=Domain(0.0, 1.0)),
    Field("yaw_inertia", unit="kg m^2", domain=Domain(1e-3, 1e9)),
    Field("lf", unit="m", domain=Domain(1e-3, 100.0)),
    Field("lr", unit="m", domain=Domain(1e-3, 100.0)),
    Field("track_front", unit="m", domain=Domain(1e-2, 100.0)),
    Field("track_rear", unit="m", domain=Domain(1e-2, 100.0)),
    Field("cg_y", unit="m", doc="the file's lateral CG", domain=Domain(-100.0, 100.0)),
)
_SPLIT = (
    Field("nominal_load_front", unit="N", domain=Domain(1.0, 1e8)),
    Field("nominal_load_rear", unit="N", domain=Domain(1.0, 1e8)),
    Field("friction", domain=Domain(1e-3, 100.0)),
    Field("load_sensitivity", domain=Domain(-100.0, 100.0)),
    Field("cornering_load", domain=Domain(1e-3, 1e3)),
)
#: Numbers the observers' discretisation is built from (folded into the step and its
#: interval): a field, but another value is refused (SET_FIXED: regenerate).
_FIXED = (
    Field("inertia", unit="kg m^2", parts=tuple(f"inertia_{w}" for w in WHEELS),
          domain=Domain(1e-6, 1e6)),
    Field("radius", unit="m", parts=tuple(f"radius_{w}" for w in WHEELS),
          domain=Domain(1e-3, 10.0)),
)  # fmt: skip
FIXED_TYRE_FIELDS = tuple(part for f in _FIXED for part in f.parts)


def tyre_parameters(vehicle: Vehicle) -> Layout:
    """The tyre step's run-time parameters of ``vehicle`` (:data:`_SETTABLE`, the split's
    numbers with a ``[cornering]`` section, then :data:`FIXED_TYRE_FIELDS`)."""
    split = _SPLIT if vehicle.cornering is not None else ()
    return Layout("tyre_params", (*_SETTABLE, *split, *_FIXED))


def tyre_parameter_values(vehicle: Vehicle) -> np.ndarray:
    """The vehicle's values of :func:`tyre_parameters`."""
    k = TyreForces(vehicle).constants
    values = {f.name: getattr(k, f.name) for f in _SETTABLE}
    values.update(inertia=k.inertia, radius=k.radius)
    if vehicle.cornering is not None:
        values.update(nominal_load_front=k.nominal_loads[0], nominal_load_rear=k.nominal_loads[1],
                      friction=k.friction, load_sensitivity=k.load_sensitivity,
                      cornering_load=k.cornering_load)  # fmt: skip
    return tyre_parameters(vehicle).pack(values)


def _symbolic_constants(constants, layout: Layout, params: ca.SX):
    """``constants`` with the settable numbers the entries of ``params``."""
    value = {name: params[layout.index(name)] for name in layout.names()}
    geometry = SimpleNamespace(**{n: value[n] for n in ("lf", "lr", "track_front", "track_rear")})
    changed = {f.name: value[f.name] for f in _SETTABLE}
    if "friction" in value:
        changed.update(nominal_loads=(value["nominal_load_front"], value["nominal_load_rear"]),
                       friction=value["friction"], load_sensitivity=value["load_sensitivity"],
                       cornering_load=value["cornering_load"])  # fmt: skip
    return dataclasses.replace(constants, positions=wheel_centres(geometry), **changed)


def tyre_kernel_function(vehicle: Vehicle, sample_interval: float) -> ca.Function:
    """``tyre_kernel(core, wheels, wheels_valid, u, u_valid, loads, mass_properties, dt,
    params)``: the force sums from the KF's input ``u`` (:data:`~wheelload.models.INPUTS`
    order, 0 where missing) and its online mass properties, then the observers' core step,
    discretised at ``sample_interval``, with the run-time numbers ``params``
    (:func:`tyre_parameters`).

    A force sum is valid where every input it depends on is (the acceleration components
    it reads, and the speed for the drag), as NaN would propagate in Python.
    """
    method = TyreForces(vehicle)
    layout = tyre_parameters(vehicle)
    core = ca.SX.sym("core", CORE.size)
    wheels = ca.SX.sym("wheels", len(WHEEL_INPUTS))
    wheels_valid = ca.SX.sym("wheels_valid", len(WHEEL_INPUTS))
    u, u_valid = ca.SX.sym("u", len(INPUTS)), ca.SX.sym("u_valid", len(INPUTS))
    loads, dt = ca.SX.sym("loads", 4), ca.SX.sym("dt")
    loaded = ca.SX.sym("mass_properties", 4)
    params = ca.SX.sym("params", layout.size)

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
    step = tyre_core_function(
        _symbolic_constants(method.constants, layout, params),
        method.settings,
        (HIGH_SLIP_Q, HIGH_SLIP_R),
        parameters=params,
    )
    outputs = step(core, wheels, wheels_valid, sums, ca.vertcat(*sums_valid), rate, rate_valid,
                   vx, vx_valid, loads, loaded, dt, observer, params)  # fmt: skip
    return ca.Function(
        "tyre_kernel",
        [core, wheels, wheels_valid, u, u_valid, loads, loaded, dt, params],
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
    layout = tyre_parameters(vehicle)
    names = layout.names()
    values = tyre_parameter_values(vehicle)
    bad = [f"{n} = {v!r}" for n, v, d in zip(names, values, layout.domains().values())
           if not d.holds(v)]  # fmt: skip
    if bad:
        raise ValueError(f"the tyre numbers are outside what the generated C accepts: {bad}")
    body = emit_statements(
        kernel,
        ["core[{}]", "wheels[{}]", "wheels_valid[{}]", "u[{}]", "u_valid[{}]", "loads[{}]",
         "mass_properties[{}]", "dt", [f"params->{n}" for n in names]],
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
        "n_tyre_params": str(len(names)),
        "tyre_param_fields": "\n".join(f"    {real} {n};" for n in names),
        "tyre_param_defaults": "\n".join(
            f"    {literal(v, precision)}, /* {n} */" for n, v in zip(names, values)
        ),
        "tyre_param_names": "\n".join(f'    "{n}",' for n in names),
        "tyre_param_cases": "\n".join(
            f"    case {k}:\n        return &params->{n};" for k, n in enumerate(names)
        ),
        "tyre_domain_code": domain_function(
            names, layout.domains(), precision, prefix, "tyre_param_in_domain"
        ),
        "tyre_fixed": ", ".join(str(int(n in FIXED_TYRE_FIELDS)) for n in names),
        "tyre_fixed_names": " ".join(FIXED_TYRE_FIELDS),
        "tyre_settable_names": " ".join(n for n in names if n not in FIXED_TYRE_FIELDS),
        "tyre_interval_tolerance": literal(
            interval_tolerance(sample_interval, precision), precision
        ),
    }
