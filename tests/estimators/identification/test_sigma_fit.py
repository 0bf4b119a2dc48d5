"""The reported sigma's calibration (estimators/identification/sigma_fit.py): what ``tune``
says of a log the calibration has not seen."""

from wheelload.estimators.identification.sigma_fit import MIN_HELD_OUT_COVERAGE, coverage_warnings


def test_a_held_out_log_below_90_percent_is_warned_with_its_figure():
    """A held-out log at 75.8 % (the docs' page after a tune on other logs) is named with
    its figure and what to do; 90 % and above are not."""
    what = "a held-out log's ±2σ coverage"
    found = coverage_warnings(
        what, [("lap.csv", 0.758), ("dlc.csv", 0.95), ("edge.csv", MIN_HELD_OUT_COVERAGE)]
    )
    assert len(found) == 1
    assert "75.8 % on lap.csv, below 90 %" in found[0] and "sigma_*" in found[0]
