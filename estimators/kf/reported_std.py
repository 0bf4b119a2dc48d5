r"""The reported standard deviation of the loads: the filter's P plus the model's mismatch.

.. math::

    \sigma_i^2 = c_0^2 P_{ii} + \sum_{k \ge 1} (c_k\, g_{ik})^2

per wheel i, with the coefficients :math:`c_k \ge 0` of the vehicle file's ``[filter]``
(``sigma_*``, :data:`~wheelload.models.vehicle.description.SIGMA_KEYS`, the end of the
tuning vector) and the features :math:`g_{ik}` of the sample, in that order:
:math:`g_{i0} = \sqrt{P_{ii}}` (the filter's own σ: it grows where rows are missing);
1 (a floor); :math:`|a_x|`, :math:`|a_y|` (load transfer the equilibrium rows get wrong
with a wrong CG or mass); :math:`|v_i|` (damper map); :math:`|d_i|` (spring rate);
:math:`|\delta_i|` with :math:`\delta = A^\top (A A^\top)^{-1} (b - A z)`, the per-wheel
load by which the suspension pseudo-measurement misses the rigid-body equilibrium
(large when the file's springs or mass are wrong or an IMU axis is biased), and its
running RMS :math:`\sqrt{\overline{\delta_i^2}}`; the suspension row's innovation
:math:`|y_i|` and its running RMS; last, for a wheel whose suspension row is missing (no
travel: its load comes from the equilibrium and the roll split alone), 1, :math:`|a_x|`,
:math:`|a_y|` (the split's and the quasi-static attitude's errors grow with the load
transfer), :math:`|a_z - g|` (heave and pitch the equilibrium cannot split; it reads
:math:`g (1 - \cos\alpha)` at rest on a grade :math:`\alpha`: the norm of the specific
force instead grows with the lateral acceleration, 0.6 kN of σ on a lap) and
:math:`|a_y - v_x \omega_z|` (:func:`~wheelload.models.body_attitude.lateral_mismatch`:
the lateral force the path's curvature does not explain; a lagging ``ay`` channel, a bank
or a sliding car move the lateral transfer the equilibrium splits without travel; 0 where
``ay``, ``vx`` or ``wz`` is missing). A running mean
is an exponentially weighted mean :math:`\bar q \leftarrow \bar q + \alpha (q - \bar q)`,
:math:`\alpha = \Delta t / (\tau + \Delta t)`, :math:`\tau` = :data:`SIGMA_TIME`, carried
in the monitor state
(:data:`~wheelload.estimators.guards.monitor_state.SIGMA_RESIDUAL`,
:data:`~wheelload.estimators.guards.monitor_state.SIGMA_INNOVATION`); a feature whose rows are
missing in a sample is 0 there (its mean held). The gain never sees σ: x and P are the
filter's own (Siegloff & Choi §III, eq. 19-25).

Example
-------
>>> g, means = sigma_features(P, u, valid, z, A, b, mask_s, mask_c, y_s, m, dt)
>>> std = reported_std(g, tuning[SIGMA_TUNING])
"""

from __future__ import annotations

import casadi as ca

from wheelload.estimators.guards import monitor_state
from wheelload.models import GRAVITY
from wheelload.models.body_attitude import lateral_mismatch
from wheelload.models.inputs import SPECIFIC_FORCE, TRAVEL, TRAVEL_RATE, input_index
from wheelload.models.vehicle.description import SIGMA_KEYS

#: Time constant of the running means [s].
SIGMA_TIME = 1.0
_TRAVEL = input_index(TRAVEL)
_RATE = input_index(TRAVEL_RATE)
_AX, _AY, _AZ = input_index(SPECIFIC_FORCE)
_VX, _WZ = input_index(("vx", "wz"))


def _running(mean, value, available, dt):
    """The running mean of ``value`` after a sample of interval ``dt`` (held if not
    ``available``)."""
    alpha = available * dt / (SIGMA_TIME + dt)
    return mean + alpha * (value - mean)


def sigma_features(P, u, valid, z, A, b, mask_s, mask_c, y_s, m, dt):
    """Features ``g`` (4 wheels x :data:`SIGMA_KEYS`) and the next running means.

    ``P``: the filter's covariance after the sample; ``u``: the sample's inputs (0 where
    missing), ``valid`` their availability; ``z, A, b``: the pseudo-measurement and the
    equilibrium rows; ``mask_s, mask_c``: their availability; ``y_s``: the suspension rows'
    innovations; ``m``: the monitor state; ``dt``: the interval used (0: skipped). Returns
    ``(g, means)``, ``means`` the monitor's next
    :data:`~wheelload.estimators.guards.monitor_state.SIGMA_SLOTS`.
    """
    every_row = mask_s[0] * mask_s[1] * mask_s[2] * mask_s[3] * mask_c[0] * mask_c[1] * mask_c[2]
    delta = ca.mtimes(A.T, ca.solve(ca.mtimes(A, A.T), b - ca.mtimes(A, z))) * every_row
    residual_mean = _running(m[monitor_state.SIGMA_RESIDUAL], delta**2, every_row, dt)
    innovation = y_s * mask_s
    innovation_mean = _running(m[monitor_state.SIGMA_INNOVATION], innovation**2, mask_s, dt)
    own = ca.sqrt(ca.fmax(ca.diag(P), 0))
    heave = ca.fabs(u[_AZ] - GRAVITY) * (u[_AZ] != 0)  # u is 0 where az is missing
    lateral = ca.fabs(lateral_mismatch(u[_AY], u[_VX], u[_WZ])) * valid[_AY] * valid[_VX]
    lateral = lateral * valid[_WZ]
    rows = []
    for i in range(4):
        rows.append(
            ca.horzcat(
                own[i],
                1,
                ca.fabs(u[_AX]),
                ca.fabs(u[_AY]),
                ca.fabs(u[_RATE[i]]) * mask_s[i],
                ca.fabs(u[_TRAVEL[i]]) * mask_s[i],
                ca.fabs(delta[i]),
                ca.sqrt(ca.fmax(residual_mean[i], 0)),
                ca.fabs(innovation[i]),
                ca.sqrt(ca.fmax(innovation_mean[i], 0)),
                1 - mask_s[i],
                ca.fabs(u[_AX]) * (1 - mask_s[i]),
                ca.fabs(u[_AY]) * (1 - mask_s[i]),
                heave * (1 - mask_s[i]),
                lateral * (1 - mask_s[i]),
            )
        )
    return ca.vertcat(*rows), ca.vertcat(residual_mean, innovation_mean)


def reported_std(g, coefficients):
    r""":math:`\sigma_i = \sqrt{\sum_k (c_k g_{ik})^2}` (never negative or NaN for finite
    inputs)."""
    weighted = g * ca.repmat(ca.reshape(coefficients, 1, len(SIGMA_KEYS)), g.shape[0], 1)
    return ca.sqrt(ca.sum2(weighted**2))
