"""Validity of the per-sample inputs ``u`` a model Function takes (``wheelload.models.inputs``).

A logged channel may be missing (NaN) for a sample: its entry of ``u`` is
then marked invalid (``valid`` 0), replaced by zero before any arithmetic
(:func:`sanitise`), and every output that structurally depends on it is
skipped (:func:`dependency_mask`, from the sparsity of the Function's
Jacobian). The KF, the MHE and the family methods gate their updates this way.
A sample interval is valid when finite, positive and below :data:`MAX_INTERVAL`
(:func:`interval_is_valid`).

Example
-------
>>> mask = dependency_mask(travel_function()(u[0:4], u[4:8], p), u, valid)
"""

from __future__ import annotations

import casadi as ca

MAX_INTERVAL = 1e6  # s, longest sample interval taken as valid


def dependency_mask(outputs: ca.SX, inputs: ca.SX, valid: ca.SX) -> ca.SX:
    """1 for each output whose every structurally needed input is valid, else 0."""
    pattern = ca.jacobian(outputs, inputs).sparsity()
    masks = []
    for row in range(outputs.shape[0]):
        needed = [col for col in range(inputs.shape[0]) if pattern.has_nz(row, col)]
        mask = 1
        for col in needed:
            mask = mask * valid[col]
        masks.append(mask)
    return ca.vertcat(*masks)


def sanitise(u: ca.SX, valid: ca.SX) -> ca.SX:
    """Replace invalid inputs by zero so that no NaN or Inf enters the arithmetic."""
    return ca.vertcat(*[ca.if_else(valid[i], u[i], 0) for i in range(u.shape[0])])


def interval_is_valid(dt):
    """1 where the sample interval is finite and positive (NaN compares false)."""
    return ca.logic_and(dt > 0, dt < MAX_INTERVAL)
