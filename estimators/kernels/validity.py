r"""Input validity inside symbolic steps: invalid inputs zeroed, rows masked by what they need.

A missing (NaN) or implausible input must neither enter the arithmetic (:func:`sanitise`)
nor feed an update: a row is taken only when every input it structurally depends on
(the sparsity of its Jacobian) is valid (:func:`dependency_mask`). A sample interval is
valid when finite and positive (:func:`interval_is_valid`).

Example
-------
>>> mask = dependency_mask(z, u, valid)  # 1 per row of z whose inputs are all valid
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
