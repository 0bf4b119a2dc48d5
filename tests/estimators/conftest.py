"""Fixtures of the KF and guard tests: a plant log, single-sample edits of it, and an independent
numpy Kalman step to check the filter against."""

import dataclasses

import numpy as np
import pytest


def predict_and_update(x, P, q, dt, H, y, r, rows):
    """Random-walk prediction :math:`P + q\\,dt\\,I`, then the scalar Joseph-form updates of the
    rows ``rows`` of :math:`y = H x` (noise variances ``r``), in order (eq. 19-25, numpy)."""
    P = P + q * dt * np.eye(4)
    for i in rows:
        h = H[i]
        S = h @ P @ h + r[i]
        K = P @ h / S
        x = x + K * (y[i] - h @ x)
        I_KH = np.eye(4) - np.outer(K, h)
        P = I_KH @ P @ I_KH.T + r[i] * np.outer(K, K)
    return x, P


@pytest.fixture(scope="session")
def numpy_step():
    """:func:`predict_and_update`: the independent reference of the filter step."""
    return predict_and_update


@pytest.fixture(scope="module")
def dlc(plant_log):
    """The ISO lane change simulated by the full-vehicle plant with the standard sensors."""
    return plant_log("iso-dlc")


def replaced_samples(signals, row, **values):
    """A copy of ``signals`` with single samples replaced: ``ax=50``, ``d_fl=0.29``, ..."""
    d, v, acc, vx = signals.d.copy(), signals.v.copy(), signals.acc.copy(), signals.vx.copy()
    for name, value in values.items():
        if name in ("ax", "ay", "az"):
            acc[row, "xyz".index(name[1])] = value
        elif name == "vx":
            vx[row] = value
        else:
            target = d if name[0] == "d" else v
            target[row, ("fl", "fr", "rl", "rr").index(name[2:])] = value
    return dataclasses.replace(signals, d=d, v=v, acc=acc, vx=vx)


@pytest.fixture(scope="session")
def with_values():
    """:func:`replaced_samples`: a log with single samples replaced."""
    return replaced_samples
