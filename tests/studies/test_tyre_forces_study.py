"""Study ``tyre-forces``: its metric and its verdict (the study itself runs ~2 min even
with --quick, so its parts are tested here and the estimators on the plant in
tests/estimators/family/test_tyre_forces.py)."""

import numpy as np
import pytest

from wheelload.studies.experiments.catalog import STUDIES
from wheelload.studies.experiments.forces.tyre_forces import goal_line, tyre_table
from wheelload.studies.metrics import pooled_force_error


def test_pooled_force_error_is_percent_of_rms():
    """A 10 % gain error on a zero-mean force is 10 % of its RMS (not of its mean)."""
    t = np.linspace(0.0, 10.0, 1001)
    reference = np.column_stack([np.sin(t + k) * 1000.0 for k in range(4)])
    rmse, rms = pooled_force_error(1.1 * reference, reference)
    assert rmse / rms == pytest.approx(0.1, rel=1e-12)
    nan = reference.copy()
    nan[3, 2] = np.nan
    assert np.isfinite(pooled_force_error(nan, reference)[0])


def test_goal_line_reads_the_worst_goal_row():
    """The verdict is computed from the lane change and the laps, not the others."""
    labels = [("car", "iso-dlc"), ("car", "hockenheim"), ("car", "standstill")]
    row = {"fx rms": 100.0, "tyre-forces fx %": 3.0, "tyre-rigid fx %": 60.0,
           "fy rms": 1000.0, "tyre-forces fy %": 8.0, "tyre-rigid fy %": 15.0}  # fmt: skip
    bad = dict(row, **{"tyre-forces fy %": 80.0})
    table = tyre_table(labels, [row, row, bad])
    assert "meets it: worst F_x 3.0 %, worst F_y 8.0 %" in goal_line(table)
    table = tyre_table(labels, [row, bad, row])
    assert "misses it" in goal_line(table) and "tyre-forces" in STUDIES
    # No lateral force at all (1e-14 N): no % rather than 1e16 %.
    straight = dict(row, **{"fy rms": 1e-14, "tyre-forces fy %": 1e16})
    assert np.isnan(tyre_table(labels[:1], [straight]).iloc[0]["Fy tyre-forces %"])
