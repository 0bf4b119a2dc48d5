r"""One step of the two-stage physics-constrained Kalman filter, as a CasADi Function.

(Siegloff & Choi §III, method A.) State :math:`x = [F_{FL}, F_{FR}, F_{RL}, F_{RR}]`,
random walk (eq. 12, 19); first update with the suspension pseudo-measurement
:math:`z = x + v_s` (eq. 13, 20-22); second update with the rigid-body equilibrium as a
soft constraint :math:`b = A x + w_c` (eq. 17, 23-25). Joseph form throughout. The noise
is built from the tuning vector (:mod:`wheelload.estimators.kf.tuning`) and the
input-dependent densities of :mod:`wheelload.models.measurement_noise`; the guards of
:mod:`wheelload.estimators.guards.settings` act on the masks of the updates.

The step is built from the model Functions in ``wheelload.models``, so the Python filter,
the compiled loops and the generated C share one implementation. It is a composition of
the stages of :func:`~wheelload.estimators.kf.stages.step_stages` (interval, payload,
plausibility and holds, model rows, fault monitor, masks, noise, predict, gate, suspension
update, equilibrium update, roll split, limits, payload update, sigma, the next monitor
state, outputs), each a named Function ``wheelload_kf_<stage>`` called on the values before
it (inlined: one expression graph).

Example
-------
>>> step = step_function()  # (x, P, m, u, u_valid, dt, p, tuning) -> (x_next, P_next, ...)
"""

from __future__ import annotations

import casadi as ca

from wheelload.estimators.guards import (
    monitor_state,
)
from wheelload.estimators.guards.monitor_state import MONITOR
from wheelload.estimators.kernels.kalman import (
    sequential_update_innovations,
)
from wheelload.estimators.kernels.stage import stage, stage_name
from wheelload.estimators.kf.stages import step_stages
from wheelload.estimators.kf.step_cache import STEP_INPUT_NAMES, STEP_NAME, STEP_OUTPUT_NAMES
from wheelload.estimators.kf.tuning import TUNING
from wheelload.models import (
    INPUTS,
    ModelParameters,
    equilibrium_function,
    suspension_function,
)
from wheelload.models.measurement_noise import measurement_noise_function

#: The stages' Functions are named ``wheelload_kf_<stage>``.
STAGE_PREFIX = "wheelload_kf"


#: Stages composed in Python, not through a Function of their own: the payload residual's
#: users. Replayed through a Function boundary, CasADi folds 12 + 9 more operations of
#: theirs (the step's 8269 instructions become 8248), so the emitted C would change.
INLINE_STAGES = ("monitor", "payload_update")


def step_expressions(
    suspension: ca.Function,
    equilibrium: ca.Function,
    *,
    constraint_update=sequential_update_innovations,
    measurement_noise: ca.Function | None = None,
):
    """Symbolic inputs and outputs of one filter step built from the model Functions.

    ``measurement_noise(u, u_valid, densities, dt_nominal) -> (R_s, R_c)``
    defaults to :func:`~wheelload.models.measurement_noise.measurement_noise_function`.

    ``constraint_update(x, P, b, A, r_c, mask, gate) -> (x, P, y, S, use)``
    is the second stage; the default is the soft-constraint Kalman update
    (eq. 23-25), one row at a time. Outputs ``innovation`` and
    ``innovation_variance`` (7 each, update order: suspension FL, FR, RL, RR,
    then vertical, pitch, roll) are each row's pre-update innovation and its
    variance S; both are 0 for a row whose inputs are missing. The guards of
    :mod:`wheelload.estimators.guards.settings` (plausibility, innovation gate, fault
    monitor with state ``m``, covariance limits) act on the masks of the
    updates, so a guarded row changes neither x nor P.

    The step is the composition of the stages of :func:`step_stages`, each a named
    Function (``wheelload_kf_<stage>``) called on the values before it.
    """
    inputs, values, _ = step_composition(
        suspension,
        equilibrium,
        constraint_update=constraint_update,
        measurement_noise=measurement_noise,
    )
    return list(inputs.values()), [values[name] for name in STEP_OUTPUT_NAMES]


def step_composition(
    suspension: ca.Function,
    equilibrium: ca.Function,
    *,
    constraint_update=sequential_update_innovations,
    measurement_noise: ca.Function | None = None,
) -> tuple[dict, dict, dict]:
    """The step's symbolic inputs, every value its stages name, and each stage's Function
    (``wheelload_kf_<stage>``; None for :data:`INLINE_STAGES`), in stage order."""
    inputs = {
        "x": ca.SX.sym("x", 4),
        "P": ca.SX.sym("P", 4, 4),
        "m": ca.SX.sym("m", MONITOR.size),
        "u_raw": ca.SX.sym("u", len(INPUTS)),
        "valid_raw": ca.SX.sym("u_valid", len(INPUTS)),
        "dt": ca.SX.sym("dt"),
        "p_file": ca.SX.sym("p", len(ModelParameters.names())),
        "tuning": ca.SX.sym("tuning", TUNING.size),
    }
    values, functions = dict(inputs), {}
    stages = step_stages(
        suspension,
        equilibrium,
        constraint_update=constraint_update,
        measurement_noise=measurement_noise or measurement_noise_function(),
    )
    for build in stages:
        name = stage_name(build)
        outputs, functions[name] = stage(
            STAGE_PREFIX, build, values, as_function=name not in INLINE_STAGES
        )
        values.update(outputs)
    return inputs, values, functions


def step_function(
    suspension: ca.Function | None = None,
    equilibrium: ca.Function | None = None,
    name: str = STEP_NAME,
    *,
    constraint_update=sequential_update_innovations,
    measurement_noise: ca.Function | None = None,
) -> ca.Function:
    """The filter step as a CasADi Function (model Functions default to ``wheelload.models``)."""
    inputs, outputs = step_expressions(
        suspension or suspension_function(),
        equilibrium or equilibrium_function(),
        constraint_update=constraint_update,
        measurement_noise=measurement_noise,
    )
    # The suspension and equilibrium share the body motion and attitude: one copy.
    outputs = ca.cse(outputs)
    return ca.Function(name, inputs, outputs, STEP_INPUT_NAMES, STEP_OUTPUT_NAMES)


def without_monitor(step: ca.Function) -> ca.Function:
    """``step`` for callers that carry only x and P: the monitor starts empty every call,
    as a started filter's (x and P are the prior, not the diffuse first sample's).

    ``(x, P, u, u_valid, dt, p, tuning) -> (x_next, P_next, std, residual,
    used, z, innovation, innovation_variance)``.
    """
    inputs = step.sx_in()
    m = ca.DM.zeros(step.sparsity_in(2))
    m[monitor_state.STARTED] = 1
    named = dict(zip(STEP_OUTPUT_NAMES, step.call([*inputs[:2], m, *inputs[3:]])))
    kept = [
        name
        for name in STEP_OUTPUT_NAMES
        if name
        not in (
            "m_next",
            "status",
            "fault_statistic",
            "fault",
            "mass_properties",
            "mass_properties_std",
        )  # fmt: skip
    ]
    names_in = [name for name in STEP_INPUT_NAMES if name != "m"]
    return ca.Function(
        f"{step.name()}_xp",
        [*inputs[:2], *inputs[3:]],
        [named[name] for name in kept],
        names_in,
        kept,
    )
