r"""The model rows of one filter step: the suspension pseudo-measurement (eq. 13) and the
rigid-body equilibrium (eq. 14-17) from the raw inputs, their validity masks, and the inputs
the fault monitor's isolated channels drop. The KF's stages and the MHE's terms share them.
"""

from __future__ import annotations

import casadi as ca

from wheelload.models import (
    INPUTS,
    OPTIONAL_INPUTS,
    gates_function,
)
from wheelload.models.input_validity import dependency_mask, sanitise
from wheelload.models.inputs import SPECIFIC_FORCE, TRAVEL, TRAVEL_RATE, input_index

#: Positions of the travels, travel rates and specific forces in the step's inputs.
TRAVEL_INDEX = input_index(TRAVEL)
RATE_INDEX = input_index(TRAVEL_RATE)
ACC_INDEX = input_index(SPECIFIC_FORCE)


def _required(valid: ca.SX) -> ca.SX:
    """Validity of the inputs an update cannot do without (optional inputs count as valid)."""
    return ca.vertcat(
        *[1 if name in OPTIONAL_INPUTS else valid[i] for i, name in enumerate(INPUTS)]
    )


def channel_drop(channel_ok: ca.SX) -> ca.SX:
    """Validity factor per input from the fault monitor's channels (d_fl..d_rr, ax, ay, az).

    A travel channel drops its travel and travel rate; an accelerometer axis drops
    that axis; every other input is kept.
    """
    factors = [1] * len(INPUTS)
    for i in range(4):
        factors[TRAVEL_INDEX[i]] = channel_ok[i]
        factors[RATE_INDEX[i]] = channel_ok[i]
    for j in range(3):
        factors[ACC_INDEX[j]] = channel_ok[4 + j]
    return ca.vertcat(*factors)


def model_rows(suspension: ca.Function, equilibrium: ca.Function, u_raw, valid, p):
    """Pseudo-measurement, equilibrium and their masks from raw inputs and validity.

    Returns ``(z, A, b, mask_s, mask_c, dropped)``. An update needs the inputs
    of the paper's model (every term gated off: the Jacobian sparsity of the
    rows with zero gates); a term whose optional input is missing is gated off
    for the sample instead, and ``dropped`` (``wheelload.models.DROPPABLE``
    order) says which.
    """
    u = sanitise(u_raw, valid)
    z, A, b, dropped = model_equations(suspension, equilibrium, u, valid, p)
    mask_s, mask_c = row_masks(suspension, equilibrium, u, u_raw, valid, p)
    return z, A, b, mask_s, mask_c, dropped


def model_equations(suspension: ca.Function, equilibrium: ca.Function, u, valid, p):
    """``(z, A, b, dropped)`` from inputs ``u`` (0 where not ``valid``) with their terms gated."""
    gates, dropped = gates_function()(valid, p)
    z = suspension(u, gates, p)
    A, b = equilibrium(u, gates, p)
    return z, A, b, dropped


def row_masks(suspension: ca.Function, equilibrium: ca.Function, u, u_raw, valid, p):
    """``(mask_s, mask_c)``: 1 for each row whose paper-model inputs are all valid."""
    paper = ca.DM.zeros(gates_function().size_out(0))
    mask_s = dependency_mask(suspension(u, paper, p), u_raw, _required(valid))
    mask_c = dependency_mask(equilibrium(u, paper, p)[1], u_raw, _required(valid))
    return mask_s, mask_c
