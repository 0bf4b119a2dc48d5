r"""Equality-constrained Kalman filter by estimate projection (Simon & Chia 2002).

The random-walk filter with the suspension update (Siegloff & Choi eq. 12-13,
19-22); the rigid-body equilibrium :math:`A x = b` (eq. 14-16) is then
imposed exactly by projecting the estimate:

.. math::
    \tilde x = \arg\min_{A x = b} (x - \hat x)^\top W (x - \hat x)
             = \hat x + K (b - A \hat x), \quad
    K = W^{-1} A^\top (A W^{-1} A^\top)^{-1}, \\
    \tilde P = (I - K A) P (I - K A)^\top

with :math:`W = P^{-1}` (maximum probability: the soft-constraint update of
eq. 23-25 in the limit :math:`R_c \to 0`) or :math:`W = I` (least squares).
The projected state and covariance are propagated. A constraint row whose
inputs are missing is left out of the projection and flagged.

Example
-------
>>> kf = ProjectionKF(vehicle, weighting=Weighting.MAXIMUM_PROBABILITY)
>>> estimate = kf.run(read_log("drive.csv"))
"""

from __future__ import annotations

import enum
import functools

import casadi as ca
import numpy as np

from wheelload.estimators.guards.settings import GuardSettings
from wheelload.estimators.kernels.kalman import ldl_solve, symmetrise
from wheelload.estimators.kf.step import step_function
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import Vehicle


class Weighting(enum.Enum):
    """The weight :math:`W` of the projection."""

    MAXIMUM_PROBABILITY = "W = P^-1"
    LEAST_SQUARES = "W = I"


def project(x, P, A, b, W_inv, mask=None):
    r"""Project ``x`` onto :math:`A x = b` in the metric :math:`W` (Simon & Chia eq. 9, 35).

    .. math::
        S = M A W^{-1} A^\top M + (I - M), \quad K = W^{-1} A^\top M S^{-1}, \\
        \tilde x = x + K M (b - A x), \quad \tilde P = (I - K A) P (I - K A)^\top

    with :math:`M = \mathrm{diag}(mask)`; a row with ``mask == 0`` is not imposed.
    """
    m, n = A.shape
    if mask is None:
        mask = ca.DM.ones(m)
    M = ca.diag(mask)
    residual = b - ca.mtimes(A, x)
    y = ca.vertcat(*[ca.if_else(mask[i], residual[i], 0) for i in range(m)])
    S = ca.mtimes([M, A, W_inv, A.T, M]) + ca.diag(1 - mask)
    K = ldl_solve(S, ca.mtimes([W_inv, A.T, M]).T).T
    G = ca.DM.eye(n) - ca.mtimes(K, A)
    return x + ca.mtimes(K, y), symmetrise(ca.mtimes([G, P, G.T]))


def projection_update(weighting: Weighting):
    """The second filter stage ``(x, P, b, A, r_c, mask, gate) -> (x, P, y, S, use)``.

    Projects and ignores ``r_c``; ``y = b - A x`` and ``S = diag(A P A^T)``
    are the rows' residuals and variances before the projection, and
    ``gate(i, y_i, S_i)`` may leave row ``i`` out of it.
    """

    def constraint_update(x, P, b, A, r_c, mask, gate=None):
        W_inv = P if weighting is Weighting.MAXIMUM_PROBABILITY else ca.DM.eye(x.shape[0])
        y = b - ca.mtimes(A, x)
        S = ca.diag(ca.mtimes([A, P, A.T]))
        if gate is not None:
            mask = ca.vertcat(*[mask[i] * gate(i, y[i], S[i]) for i in range(A.shape[0])])
        x_new, P_new = project(x, P, A, b, W_inv, mask)
        return x_new, P_new, y, S, mask

    return constraint_update


STEP_NAMES = {
    Weighting.MAXIMUM_PROBABILITY: "wheelload_projection_kf_mp_step",
    Weighting.LEAST_SQUARES: "wheelload_projection_kf_ls_step",
}


@functools.cache
def projection_step_function(weighting: Weighting) -> ca.Function:
    """The projection-filter step, with the inputs and outputs of the two-stage step."""
    return step_function(name=STEP_NAMES[weighting], constraint_update=projection_update(weighting))


class ProjectionKF(TwoStageKF):
    """Projection Kalman filter: suspension update, then exact projection onto :math:`A x = b`.

    Parameters
    ----------
    vehicle
        Vehicle parameters and filter tuning (the constraint noise is unused).
    weighting
        :attr:`Weighting.MAXIMUM_PROBABILITY` (:math:`W = P^{-1}`) or
        :attr:`Weighting.LEAST_SQUARES` (:math:`W = I`).
    static
        Static wheel loads [N]; default: the vehicle file's.
    guard_settings
        The guards (:class:`~wheelload.estimators.guards.settings.GuardSettings`); default:
        the file's.
    check_file
        As :class:`~wheelload.estimators.kf.two_stage.TwoStageKF`'s.
    """

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        weighting: Weighting = Weighting.MAXIMUM_PROBABILITY,
        static: np.ndarray | None = None,
        guard_settings: GuardSettings | None = None,
        check_file: bool = True,
    ) -> None:
        if not isinstance(weighting, Weighting):
            raise TypeError(f"weighting must be a Weighting, got {weighting!r}")
        step = projection_step_function(weighting)
        super().__init__(
            vehicle, static=static, step=step, guard_settings=guard_settings,
            check_file=check_file,
        )  # fmt: skip
        self.weighting = weighting
        self.name = f"projection KF ({weighting.value})"
