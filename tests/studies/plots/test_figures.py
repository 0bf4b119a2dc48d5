"""Figures on the bundled example log (Agg backend), checked on their artists.

Every method of the registry is run once on the log (``compare_methods``); the figures'
lines are compared with the estimates and the reference they must hold, to 1e-12 kN
(the figures store loads / 1000 in float64: exact up to one rounding).
"""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from wheelload.estimators import StepFlag, read_log
from wheelload.estimators.estimate_figure import CONSERVATIVE  # noqa: E402
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.registry import methods  # noqa: E402
from wheelload.models import example_vehicle_path, load_vehicle  # noqa: E402
from wheelload.studies.experiments.report.figures import loads_figure  # noqa: E402
from wheelload.studies.identical import (  # noqa: E402
    TOLERANCE,
    collapse,
    identical_groups,
    identity_notes,
)
from wheelload.studies.pipeline.batch import EstimateSettings, estimate_log  # noqa: E402
from wheelload.studies.pipeline.comparison import compare_methods, format_table  # noqa: E402
from wheelload.studies.pipeline.example_log import example_log_path  # noqa: E402
from wheelload.studies.plots.comparison import comparison_figure  # noqa: E402
from wheelload.studies.plots.estimate import plot_estimate  # noqa: E402

EXACT = 1e-12  # kN: loads / 1000 in float64, one rounding
PAIR = ("projection-mp", "projection-ls")
COLLAPSED = "projection-mp = projection-ls"


@pytest.fixture(scope="module")
def signals():
    return read_log(example_log_path())


@pytest.fixture(scope="module")
def comparison(signals):
    vehicle = load_vehicle(example_vehicle_path())
    return compare_methods(signals, vehicle, tuple(methods()), repeat=1)


@pytest.fixture(scope="module")
def front_left(comparison, signals):
    return comparison_figure(comparison, signals, 0, "example")


def _method_axes(figure):
    """The comparison figure's method panels (all but the error panel, the last axes)."""
    return figure.axes[:-1]


def _line(ax, label):
    (line,) = [line for line in ax.get_lines() if line.get_label() == label]
    return line


def test_no_two_methods_share_colour_and_line_style(front_left, comparison):
    looks = {}
    for ax in _method_axes(front_left):
        for line in ax.get_lines():
            if line.get_label() != "reference":
                looks[line.get_label()] = (to_rgba(line.get_color()), line.get_linestyle())
    distinct = [name for name, _ in comparison.distinct()]
    assert list(looks) == distinct  # one panel a method, identical methods once
    assert len(set(looks.values())) == len(looks)
    assert all(colour != to_rgba("black") for colour, _ in looks.values())


def test_each_panel_holds_its_method_under_the_reference(front_left, comparison, signals):
    for ax, (name, result) in zip(_method_axes(front_left), comparison.distinct()):
        estimate, reference = _line(ax, name), _line(ax, "reference")
        np.testing.assert_allclose(estimate.get_ydata(), result.estimate.loads[:, 0] / 1000.0,
                                   rtol=0, atol=EXACT)  # fmt: skip
        np.testing.assert_allclose(reference.get_ydata(), signals.reference[:, 0] / 1000.0,
                                   rtol=0, atol=EXACT)  # fmt: skip
        others = [a.get_zorder() for a in (*ax.lines, *ax.collections, *ax.patches)
                  if a is not reference]  # fmt: skip
        assert reference.get_zorder() > max(others)
        assert to_rgba(reference.get_color()) == to_rgba("black")
        assert reference.get_linewidth() > estimate.get_linewidth()


def test_the_error_panel_holds_every_methods_99th_percentile(front_left, comparison, signals):
    ax = front_left.axes[-1]
    bottom, top = ax.get_ylim()
    # Independent: |error| of each method over the scored window (the whole log here).
    percentiles = [
        np.percentile(np.abs(result.estimate.loads[:, 0] - signals.reference[:, 0]), 99.0)
        for _, result in comparison.distinct()
    ]
    assert bottom == 0.0
    assert top >= max(percentiles)  # nothing's 99th percentile clipped
    assert top <= 1.1 * max(percentiles) * (1 + 1e-9)  # the axis is set from the data
    assert "99th percentile" in ax.get_ylabel()
    assert [t.get_text() for t in ax.get_xticklabels()] == [n for n, _ in comparison.distinct()]


def test_the_projection_pair_is_shown_once_with_a_note(front_left, comparison):
    loads = comparison.loads()
    difference = np.max(np.abs(loads[PAIR[0]] - loads[PAIR[1]]))
    assert difference < TOLERANCE  # independent of identical_groups
    assert PAIR in comparison.identical()
    assert np.max(np.abs(loads["kf"] - loads[PAIR[0]])) > 1.0  # N: the KF is not the pair
    assert ("kf",) in comparison.identical()
    titles = [ax.get_title() for ax in _method_axes(front_left)]
    assert sum(title.startswith(COLLAPSED + ":") for title in titles) == 1
    assert not any(title.startswith(f"{PAIR[1]}:") for title in titles)
    caption = " ".join(text.get_text() for text in front_left.texts)
    assert COLLAPSED in caption and "P ∝ I" in caption
    table = format_table(comparison)
    rows = [line for line in table.splitlines() if COLLAPSED in line and "note" not in line]
    assert len(rows) == 4  # RMSE, RMSE %, P95, Max
    metric_rows = table.split("time per sample")[0]
    assert f" {PAIR[1]} " not in metric_rows.replace(COLLAPSED, "")
    assert "note: " + COLLAPSED in table and "P ∝ I" in table


def test_a_difference_above_the_tolerance_keeps_the_methods_apart(comparison):
    loads = comparison.loads()
    nudged = loads[PAIR[1]].copy()
    nudged[100, 2] += 10 * TOLERANCE
    groups = identical_groups({PAIR[0]: loads[PAIR[0]], PAIR[1]: nudged})
    assert groups == ((PAIR[0],), (PAIR[1],))
    assert identity_notes({PAIR[0]: loads[PAIR[0]], PAIR[1]: nudged}, groups) == ()
    values = {"kf": 1, PAIR[0]: 2, PAIR[1]: 3, "C": 4}
    assert collapse(values, ((PAIR[0], PAIR[1]),)) == {"kf": 1, COLLAPSED: 2, "C": 4}


def test_the_study_loads_figure_is_small_multiples(comparison, signals):
    estimates = collapse({r.info.name: r.estimate.loads for r in comparison.results},
                         comparison.identical())  # fmt: skip
    figure = loads_figure(signals.t, signals.reference, estimates, "example", comparison.notes())
    assert len(figure.axes) == 4 * len(estimates)  # a row per method, a column per wheel
    for k, ax in enumerate(figure.axes):
        name = list(estimates)[k // 4]
        assert [line.get_label() for line in ax.get_lines()] == [name, "reference"]
        estimate, reference = ax.get_lines()
        np.testing.assert_allclose(estimate.get_ydata(), estimates[name][:, k % 4] / 1000.0,
                                   rtol=0, atol=EXACT)  # fmt: skip
        assert reference.get_zorder() > estimate.get_zorder()
    assert any(COLLAPSED in text.get_text() for text in figure.texts)


@pytest.fixture(scope="module")
def kf_estimate():
    return estimate_log(example_log_path(), EstimateSettings(vehicle=example_vehicle_path()))


def test_estimate_plot_holds_the_estimate_its_band_and_the_reference(kf_estimate):
    estimate, signals = kf_estimate.estimate, kf_estimate.signals
    figure = estimate.plot(signals.reference)
    assert isinstance(figure, Figure) and len(figure.axes) == 4
    for i, ax in enumerate(figure.axes):
        line, reference = _line(ax, "estimate"), _line(ax, "reference")
        np.testing.assert_allclose(line.get_xdata(), estimate.t, rtol=0, atol=0)
        np.testing.assert_allclose(line.get_ydata(), estimate.loads[:, i] / 1000.0,
                                   rtol=0, atol=EXACT)  # fmt: skip
        np.testing.assert_allclose(reference.get_ydata(), signals.reference[:, i] / 1000.0,
                                   rtol=0, atol=EXACT)  # fmt: skip
        assert reference.get_zorder() == max(a.get_zorder() for a in (*ax.lines, *ax.collections))
        (band,) = ax.collections
        corners = np.concatenate([path.vertices for path in band.get_paths()])
        upper = (estimate.loads[:, i] + 2.0 * estimate.std[:, i]) / 1000.0
        lower = (estimate.loads[:, i] - 2.0 * estimate.std[:, i]) / 1000.0
        assert corners[:, 1].max() == pytest.approx(upper.max(), abs=EXACT)
        assert corners[:, 1].min() == pytest.approx(lower.min(), abs=EXACT)
        # The coverage in the title, computed here from the arrays.
        error = estimate.loads[:, i] - signals.reference[:, i]
        covered = np.mean(np.abs(error) < 2.0 * estimate.std[:, i])
        assert f"|error| < 2σ in {covered:.1%}" in ax.get_title()
    caption = " ".join(text.get_text() for text in figure.texts).replace("\n", " ")
    assert "σ as the estimator reports it" in caption
    # The pooled coverage and the band-to-error ratio, computed here from the arrays.
    error = estimate.loads - signals.reference
    pooled = np.mean(np.abs(error) < 2.0 * estimate.std)
    ratio = np.median(2.0 * estimate.std) / np.sqrt(np.mean(error**2))
    assert f"< 2σ) {pooled:.1%}" in caption and f"median 2σ = {ratio:.1f} ×" in caption


def test_the_smoothed_band_is_named_the_rts_covariance_and_called_conservative(signals):
    """The smoother's σ is its RTS covariance: drawn as given, its source and verdict said."""
    smoothed = TwoStageKF(load_vehicle(example_vehicle_path())).smooth(signals)
    figure = smoothed.plot(signals.reference)
    caption = " ".join(text.get_text() for text in figure.texts).replace("\n", " ")
    error = np.abs(smoothed.loads - signals.reference)
    pooled = np.mean(error < 2.0 * smoothed.std)
    assert pooled > CONSERVATIVE  # the measured 100 %: the band wider than every error
    assert "RTS covariance" in caption and f"< 2σ) {pooled:.1%}" in caption
    assert "σ conservative" in caption
    for i, ax in enumerate(figure.axes):
        (band,) = ax.collections
        corners = np.concatenate([path.vertices for path in band.get_paths()])
        upper = (smoothed.loads[:, i] + 2.0 * smoothed.std[:, i]) / 1000.0
        assert corners[:, 1].max() == pytest.approx(upper.max(), abs=EXACT)
    assert "std: the RTS covariance" in repr(smoothed) and len(repr(smoothed)) < 200


def test_estimate_plot_with_errors_draws_the_band_around_zero(kf_estimate, tmp_path):
    estimate, signals = kf_estimate.estimate, kf_estimate.signals
    figure = estimate.plot(signals.reference, errors=True)
    assert len(figure.axes) == 8  # four wheels, each with its error panel below
    for i, ax in enumerate(figure.axes[1::2]):
        line = _line(ax, "estimate − reference")
        np.testing.assert_allclose(line.get_ydata(), estimate.loads[:, i] - signals.reference[:, i],
                                   rtol=0, atol=0)  # fmt: skip
        (band,) = ax.collections
        corners = np.concatenate([path.vertices for path in band.get_paths()])
        assert corners[:, 1].max() == pytest.approx(2.0 * estimate.std[:, i].max(), rel=1e-12)
    path = plot_estimate(estimate, signals, tmp_path / "estimate.png")
    assert path.stat().st_size > 20_000


def test_estimate_plot_refuses_a_reference_of_other_samples(kf_estimate):
    estimate, signals = kf_estimate.estimate, kf_estimate.signals
    with pytest.raises(ValueError, match="same samples"):
        estimate.plot(signals.reference[:-1])


def test_estimate_repr_is_one_short_line(kf_estimate, comparison, signals):
    text = repr(kf_estimate.estimate)
    assert len(text) < 200 and "\n" not in text and "[" not in text  # no arrays
    assert "method='kf'" in text and f"samples={len(signals.t)}" in text
    assert f"t={signals.t[0]:.2f}..{signals.t[-1]:.2f} s" in text
    mhe = next(r.estimate for r in comparison.results if r.info.name == "mhe")
    text = repr(mhe)
    assert text.startswith("MheEstimate(method='mhe', ") and len(text) < 200
    skipped = np.count_nonzero(mhe.flags.astype(np.int64) & StepFlag.skipped_mask())
    assert f"flags: {skipped} skipped" in text
