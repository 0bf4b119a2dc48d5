"""Study ``tyre-forces``: its metric and its verdict (the study itself runs ~2 min even
with --quick, so its parts are tested here and the estimators on the plant in
tests/estimators/family/tyres/test_tyre_forces.py)."""

import numpy as np
import pytest

from wheelload.studies.experiments.catalog import STUDIES
from wheelload.studies.experiments.forces.tyre_forces import (
    ABS_TCS,
    firing_line,
    goal_line,
    tyre_table,
)
from wheelload.studies.metrics import normalized_rms_error, pooled_force_error


def test_pooled_force_error_is_percent_of_rms():
    """A 10 % gain error on a zero-mean force is 10 % of its RMS (not of its mean)."""
    t = np.linspace(0.0, 10.0, 1001)
    reference = np.column_stack([np.sin(t + k) * 1000.0 for k in range(4)])
    rmse, rms = pooled_force_error(1.1 * reference, reference)
    assert rmse / rms == pytest.approx(0.1, rel=1e-12)
    nan = reference.copy()
    nan[3, 2] = np.nan
    assert np.isfinite(pooled_force_error(nan, reference)[0])


def test_normalized_rms_error_is_the_papers_rho():
    """ρe per wheel by hand: errors (3, -4) on a reference whose largest |value| is 10 give
    sqrt(12.5) / 10 = 35.36 %; a missing sample is left out; a wheel with a zero reference
    has no ρe (NaN, not inf)."""
    reference = np.array([[10.0, -2.0, 0.0, 5.0], [2.0, 4.0, 0.0, np.nan]])
    estimate = reference + np.array([[3.0, 1.0, 1.0, 1.0], [-4.0, 1.0, 1.0, 1.0]])
    rho = normalized_rms_error(estimate, reference)
    np.testing.assert_allclose(rho[:2], [100 * np.sqrt(12.5) / 10, 100 * 1.0 / 4], rtol=1e-12)
    assert np.isnan(rho[2]) and rho[3] == pytest.approx(100 * 1.0 / 5.0, rel=1e-12)


ROW = {"fx rms": 100.0, "tyre-forces fx %": 3.0, "tyre-rigid fx %": 60.0,
       "tyre-forces fx nrms": 2.0, "fy rms": 1000.0, "tyre-forces fy %": 8.0,
       "tyre-rigid fy %": 15.0, "tyre-forces fy nrms": 5.0, "high slip %": 0.0}  # fmt: skip


def test_goal_line_reads_the_worst_goal_row():
    """The verdict is computed from the lane change and the laps on the exact file, not the
    other scenarios or conditions."""
    labels = [("car", "iso-dlc", "exact"), ("car", "hockenheim", "exact"),
              ("car", "standstill", "exact"), ("car", "iso-dlc", "torque +5 %")]  # fmt: skip
    bad = dict(ROW, **{"tyre-forces fy %": 80.0})
    table = tyre_table(labels, [ROW, ROW, bad, bad])
    assert "meets it: worst F_x 3.0 %, worst F_y 8.0 %" in goal_line(table)
    table = tyre_table(labels, [ROW, bad, ROW, ROW])
    assert "misses it" in goal_line(table) and "tyre-forces" in STUDIES
    # No lateral force at all (1e-14 N): no % rather than 1e16 %.
    straight = dict(ROW, **{"fy rms": 1e-14, "tyre-forces fy %": 1e16})
    assert np.isnan(tyre_table(labels[:1], [straight]).iloc[0]["Fy tyre-forces %"])


def test_firing_line_reads_each_road_and_the_switch():
    """The high-slip shares are read per condition on the Table I manoeuvres, on the kerb
    and the laps; the switch's F_y change is its row less the exact file's."""
    cases = (("iso-dlc", "exact"), ("brake-in-turn", "exact"), ("brake-in-turn", "μ 0.3"),
             ("wheel-lift", "exact"), ("hockenheim", "exact"),
             ("hockenheim", "paper's switching"))  # fmt: skip
    labels = [("car", scenario, condition) for scenario, condition in cases]
    shares = (0.0, 1.0, 12.5, 2.0, 4.0, 4.0)
    rows = [dict(ROW, **{"high slip %": share}) for share in shares]
    rows[-1]["tyre-forces fy %"] = 9.5
    words = firing_line(tyre_table(labels, rows))
    assert "Table I manoeuvres on exact 0.0-1.0 %, μ 0.3 12.5-12.5 %" in words
    assert "on the kerb (exact file) 2.0-2.0 %; on the laps (exact file) 4.0-4.0 %" in words
    assert "moved F_y by +1.5 to +1.5 points on its rows (paper's switching against exact)" in words


def test_firing_line_reads_the_switch_beyond_the_grip():
    """Beyond the grip the switch is read against the same runs without it, and the
    ABS/TCS rows' shares are listed with the other conditions'."""
    cases = (("brake-in-turn", ABS_TCS), ("accel-in-turn", ABS_TCS),
             ("brake-in-turn", f"{ABS_TCS}, switching"),
             ("accel-in-turn", f"{ABS_TCS}, switching"))  # fmt: skip
    labels = [("car", scenario, condition) for scenario, condition in cases]
    rows = [dict(ROW, **{"high slip %": share, "tyre-forces fy %": fy})
            for share, fy in ((3.0, 10.0), (1.0, 12.0), (3.0, 9.0), (1.0, 12.5))]  # fmt: skip
    words = firing_line(tyre_table(labels, rows))
    assert f"{ABS_TCS} 1.0-3.0 %, {ABS_TCS}, switching 1.0-3.0 %" in words
    assert f"by -1.0 to +0.5 points on its rows ({ABS_TCS}, switching against {ABS_TCS})" in words
