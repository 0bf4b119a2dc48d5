r"""Method E+C: the quarter-car observer followed by the soft equilibrium update (§IV-E2).

The structural study of Siegloff & Choi §IV-E2 ("Cheon + Constraint Kalman
Filter"): the two-stage filter of §III with the four observer outputs of
method E (:mod:`wheelload.estimators.family.quarter_car`) in place of the
suspension pseudo-measurement. Random walk :math:`x^- = x`,
:math:`P^- = P + q\Delta t I` (eq. 19); update with :math:`z = \hat F_E`,
:math:`R_s` (eq. 20-22); soft equilibrium update :math:`b = A x + w_c`,
:math:`R_c` (eq. 23-25), all with the kernels of
:mod:`wheelload.estimators.kernels.kalman` and the vehicle file's filter tuning, as the
two-stage KF: :math:`R_s, R_c` are the KF's Function
(:mod:`wheelload.models.measurement_noise`) at the sample's interval, so
:math:`r_s/\Delta t\,I`, :math:`\mathrm{diag}(r_c)/\Delta t` with the default zero
input-dependent densities, and the same per-sample noise as the KF's rows with
a tuned file. A corner whose observer
was held is not used in the first update; a constraint row with a missing
input is skipped; both are flagged. The observers and the equilibrium use
the vehicle model chosen by ``suspension`` (default the KF's full model,
:mod:`~wheelload.estimators.family.suspension_model`).
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from wheelload.estimators.family.flat_step import model_equilibrium, step_function, step_symbols
from wheelload.estimators.family.quarter_car import (
    FRONT_END_CONSTANTS,
    FRONT_END_STATES,
    QuarterCarObserver,
    QuarterCarOptions,
    front_end,
)
from wheelload.estimators.kernels.kalman import predict, sequential_update, upper
from wheelload.estimators.kf.tuning import TUNING, tuning_vector
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.models.measurement_noise import DENSITIES, measurement_noise_function

N_STATES = FRONT_END_STATES + 4 + 16  # observer, x, P (column-major)


@functools.cache
def constrained_step(model: SuspensionModel = DEFAULT_MODEL) -> ca.Function:
    """Step: state = (observer, x, P); constants = (observer constants, KF tuning)."""
    sym = step_symbols(N_STATES, FRONT_END_CONSTANTS + TUNING.size)
    observer, F, used_s = front_end(
        sym, sym.s[:FRONT_END_STATES], sym.c[:FRONT_END_CONSTANTS], model
    )
    x = sym.s[FRONT_END_STATES : FRONT_END_STATES + 4]
    P = ca.reshape(sym.s[FRONT_END_STATES + 4 :], 4, 4)
    tuning = sym.c[FRONT_END_CONSTANTS:]
    A, b, mask_c = model_equilibrium(model, sym)
    mask_c = mask_c * sym.dt_ok
    Q = TUNING.value(tuning, "process_noise_density") * sym.dt * ca.DM.eye(4)
    densities = TUNING.values(tuning, DENSITIES)
    rs, rc = measurement_noise_function()(sym.u, sym.valid, densities, sym.dt)
    x_pred, P_pred = predict(x, upper(P), Q)
    x_s, P_s = sequential_update(x_pred, P_pred, F, ca.DM.eye(4), rs, used_s)
    x_new, P_new = sequential_update(x_s, P_s, b, A, rc, mask_c)
    std = ca.sqrt(ca.fmax(ca.diag(P_new), 0))
    s_next = ca.vertcat(observer, x_new, ca.vec(P_new))
    return step_function(
        "wheelload_quarter_car_constrained_step", model, sym, s_next, x_new, std, used_s,
        (A, b, mask_c),
    )  # fmt: skip


class ConstrainedQuarterCar(QuarterCarObserver):
    """Method E+C: quarter-car observers + the two-stage KF's updates (module docstring)."""

    name = "E+C quarter-car + constraint"
    has_std = True

    def build_step(self) -> ca.Function:
        return constrained_step(self.suspension)

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        (observer,) = super().initial_arrays()
        P0 = self.vehicle.filter.initial_std**2 * np.eye(4)
        return (np.concatenate([observer, self.parameters.static(), P0.ravel(order="F")]),)

    def constants(self) -> np.ndarray:
        return np.concatenate([super().constants(), tuning_vector(self.vehicle)])


INFO = MethodInfo(
    name="E+C",
    description="method E's observers followed by the KF's soft equilibrium update",
    reference="Siegloff & Choi §IV-E2 (Cheon + constraint KF); eq. 19-25",
    build=ConstrainedQuarterCar,
    options=QuarterCarOptions,
    model_choice=True,
)
