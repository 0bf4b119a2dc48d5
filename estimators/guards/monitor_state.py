"""Layout of the filter step's carried guard state ``m`` (fault monitor, gate, held inputs).

One vector carried from sample to sample by the step (input ``m``, output ``m_next``): the
fault monitor's slots (:mod:`.fault_monitor`), the innovation gate's rejection times and
spreads (:mod:`.innovation_gate`), then each input's held value and hold time, the rate
derivatives' settle times (:mod:`wheelload.estimators.guards.plausibility`), the range of the
vertical row (:mod:`.limits`), the reported sigma's running means (:mod:`.reported_std`)
and the payload filter (:mod:`wheelload.estimators.kf.payload`). It starts at zero.

Example
-------
>>> m = np.zeros(MONITOR_SIZE)
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.inputs import BODY_RATES, INPUTS

# Layout of the monitor state ``m``.
D_PREV, FROZEN, RBAR = slice(0, 4), slice(4, 8), slice(8, 11)
PERSIST, CLEAR, FAULT, REJECT = slice(11, 18), slice(18, 25), slice(25, 32), slice(32, 39)
SPREAD, ANCHOR, MOVED, JUMP = slice(39, 46), slice(46, 50), slice(50, 54), slice(54, 58)
PARITY_MEAN, PARITY_VARIANCE, PARITY_WEIGHT = slice(58, 61), slice(61, 64), slice(64, 65)
# The low-passed covariance the unknown payload leaves in the residual (upper triangle:
# 00, 01, 02, 11, 12, 22), beside the low-passed residual it may explain.
UNEXPLAINED = slice(65, 71)
# Each accelerometer axis' excitation (ax, ay, az - g), low-passed like the residual, and
# per axis the weighted means of the bias/gain split (fault_monitor.gain_bias_split).
EXCITATION = slice(71, 74)
GAIN_SUMS = slice(74, 89)
#: Slots of the fault monitor proper; the held inputs follow (:func:`hold_inputs`).
MONITOR_END = 89
# Each input's last valid value, its remaining hold time, and each rate derivative's
# remaining settle time after a gated rate.
HELD = slice(MONITOR_END, MONITOR_END + len(INPUTS))
CREDIT = slice(HELD.stop, HELD.stop + len(INPUTS))
SETTLE = slice(CREDIT.stop, CREDIT.stop + len(BODY_RATES))
# Lowest and highest vertical-row b seen so far, less the weight (0 at the start).
TOTAL = slice(SETTLE.stop, SETTLE.stop + 2)
# The reported sigma's running means (:mod:`.reported_std`): per wheel the squared
# equilibrium residual at the pseudo-measurement, then the squared suspension innovation.
SIGMA_RESIDUAL = slice(TOTAL.stop, TOTAL.stop + 4)
SIGMA_INNOVATION = slice(SIGMA_RESIDUAL.stop, SIGMA_RESIDUAL.stop + 4)
SIGMA_SLOTS = slice(SIGMA_RESIDUAL.start, SIGMA_INNOVATION.stop)
# The payload filter (:mod:`.payload`): its state and covariance (column-major); whether the
# step has taken a sample (0: the payload prior is taken on the next one); whether each
# travel channel has had a valid sample (0: it has no previous value to jump from).
PAYLOAD = slice(SIGMA_SLOTS.stop, SIGMA_SLOTS.stop + 4)
PAYLOAD_COVARIANCE = slice(PAYLOAD.stop, PAYLOAD.stop + 16)
STARTED = PAYLOAD_COVARIANCE.stop
TRAVEL_SEEN = slice(STARTED + 1, STARTED + 5)
MONITOR_SIZE = TRAVEL_SEEN.stop


def with_hold_state(m_next: ca.SX, hold_state: ca.SX, settle: ca.SX, total: ca.SX) -> ca.SX:
    """The fault monitor's next state, then the held inputs, settle times and total range."""
    return ca.vertcat(m_next[0:MONITOR_END], hold_state, settle, total)


def with_payload_state(m_next: ca.SX, theta: ca.SX, P: ca.SX, started: ca.SX, seen: ca.SX) -> ca.SX:
    """The guards' next state (up to :data:`PAYLOAD`), the payload filter's, started, and
    the travel channels seen."""
    return ca.vertcat(m_next[0 : PAYLOAD.start], theta, ca.vec(P), started, seen)


def with_gate_state(m_next: ca.SX, times: ca.SX, spread: ca.SX) -> ca.SX:
    """The monitor state with the rows' rejection times and innovation spreads replaced."""
    return ca.vertcat(m_next[0 : REJECT.start], times, spread, m_next[SPREAD.stop :])


def with_sigma_state(m_next: ca.SX, means: ca.SX) -> ca.SX:
    """The monitor state up to the reported sigma's slots, then its running means."""
    return ca.vertcat(m_next[0 : SIGMA_SLOTS.start], means)
