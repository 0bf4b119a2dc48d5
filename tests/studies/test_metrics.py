"""Paper metrics (eq. 26-34) against a hand computation."""

import numpy as np
import pytest

from wheelload.studies.metrics import pooled_metrics, wheel_metrics


def test_metrics_match_hand_computation():
    reference = np.array([[1000.0, 2000.0, 3000.0, 4000.0]] * 4)
    errors = np.array([[10.0, 0, 0, 0], [-10.0, 0, 0, 0], [10.0, 0, 0, 0], [-10.0, 0, 0, 40.0]])
    table = wheel_metrics(reference + errors, reference)
    assert table.loc["fl", "RMSE"] == pytest.approx(10.0)
    assert table.loc["fl", "RMSE %"] == pytest.approx(1.0)
    assert table.loc["rr", "Max"] == pytest.approx(40.0)
    assert table.loc["rr", "RMSE"] == pytest.approx(20.0)
    pooled = pooled_metrics(reference + errors, reference)
    assert pooled["RMSE"] == pytest.approx(np.sqrt((4 * 100 + 1600) / 16))
    assert pooled["RMSE %"] == pytest.approx(100 * pooled["RMSE"] / 2500.0)
    assert pooled["P95"] == pytest.approx(np.percentile(np.abs(errors), 95))


def test_non_finite_samples_are_left_out_and_counted():
    reference = np.full((3, 4), 1000.0)
    estimate = reference + 5.0
    estimate[1, 2] = np.nan
    table = wheel_metrics(estimate, reference)
    assert table.loc["pooled", "samples"] == 2
    assert table.loc["pooled", "RMSE"] == pytest.approx(5.0)


def test_wheels_without_a_reference_are_left_out():
    reference = np.full((5, 4), np.nan)
    reference[:, :2] = [3000.0, 4000.0]  # front wheels only
    estimate = np.full((5, 4), 3500.0)
    estimate[:, 0] = 3000.0 + np.array([10.0, -10.0, 10.0, -10.0, 10.0])
    table = wheel_metrics(estimate, reference)
    assert list(table.index) == ["fl", "fr", "pooled"]
    assert table.loc["fl", "RMSE"] == pytest.approx(10.0)
    assert table.loc["fr", "RMSE"] == pytest.approx(500.0)
    assert table.loc["pooled", "RMSE"] == pytest.approx(np.sqrt((100.0 + 500.0**2) / 2))
    assert table.loc["pooled", "samples"] == 5


def test_no_reference_at_all_names_the_log():
    with pytest.raises(ValueError, match=r"drive.csv: no wheel has a finite reference"):
        wheel_metrics(np.ones((3, 4)), np.full((3, 4), np.nan), source="drive.csv")
