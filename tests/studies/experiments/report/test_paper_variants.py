"""The paper-faithful study set-ups (issue 25): ablation edits that change one thing, the
baseline-variant list of REPORT.md, the Monte Carlo trend sentence."""

from __future__ import annotations

import tomllib
from dataclasses import replace

import pytest

from wheelload.estimators import SuspensionModel
from wheelload.estimators.registry import methods
from wheelload.models import ModelParameters, example_vehicle_path
from wheelload.models.vehicle.description import vehicle_from_dict
from wheelload.studies.experiments.report.shape import changes_from
from wheelload.studies.experiments.report.variants import VARIANTS, Fidelity, variants_markdown
from wheelload.studies.experiments.runs.estimator_model import EstimatorModel
from wheelload.studies.experiments.vehicle_file_ablation import ablation_variants


def _parameters(text: str) -> ModelParameters:
    return ModelParameters.from_vehicle(vehicle_from_dict(tomllib.loads(text)))


def test_ablation_edits_change_one_thing():
    """No aero: lift 0, drag kept; no ARB: bars 0, the filter's roll split the unedited
    file's (a bar rate of 0 alone would move it: the default is the bars' and springs' share);
    every other parameter equal."""
    text = example_vehicle_path().read_text(encoding="utf-8")
    base = _parameters(text)
    variants = {v.label: v for v in ablation_variants(text)}
    cases = {label: _parameters(variants[label].apply(text)) for label in ("no aero", "no ARB")}
    changed = {
        label: {
            name
            for name, value in vars(p).items()
            if not isinstance(value, tuple)
            and float(value) != pytest.approx(float(getattr(base, name)), rel=1e-8)
        }
        for label, p in cases.items()
    }
    assert changed["no aero"] == {"lift_coefficient"}
    assert changed["no ARB"] == {"arb_rate_front", "arb_rate_rear"}
    assert cases["no ARB"].roll_split_front == pytest.approx(base.roll_split_front, abs=1e-9)
    bare = vehicle_from_dict(tomllib.loads(text))
    axles = {a: replace(getattr(bare.suspension, a), arb_rate=0.0) for a in ("front", "rear")}
    bars_off = bare.replace(suspension=replace(bare.suspension, **axles))
    unheld = float(ModelParameters.from_vehicle(bars_off).roll_split_front)
    assert abs(unheld - base.roll_split_front) > 0.005  # what holding prevents


def test_every_baseline_variant_is_registered_and_c_has_both():
    registered = set(methods())
    assert {v.method for v in VARIANTS} <= registered
    c = {v.method: v for v in VARIANTS if v.paper == "C"}
    assert c["C"].paper_model is Fidelity.STRENGTHENED
    assert c["C-paper"].paper_model is Fidelity.PAPER_FAITHFUL
    assert {v.paper for v in VARIANTS} == set("ABCDEF")
    text = variants_markdown(SuspensionModel.PAPER, EstimatorModel.FULL)
    assert "| C-paper | paper-faithful |" in text and "| C | strengthened |" in text
    # the kf's variant follows --model, the family methods' --suspension
    assert "| A | kf | strengthened |" in text and "| B | B | paper-faithful |" in text
    text = variants_markdown(SuspensionModel.FULL, EstimatorModel.PAPER)
    assert "| A | kf | paper-faithful |" in text and "| B | B | strengthened |" in text


def test_trend_sentence_is_computed_from_the_numbers():
    ours = {1.0: 100.0, 2.0: 110.0, 16.0: 300.0}
    paper = {1.0: 200.0, 2.0: 201.0, 16.0: 204.0}
    sentence = changes_from(ours, paper, 1.0, "the mean")
    assert "+10.0 % (paper +0.5 %) at 2" in sentence
    assert "+200.0 % (paper +2.0 %) at 16" in sentence


def test_monte_carlo_tables_set_each_variant_beside_the_papers_cells():
    """Made-up trials (RMSE = 100 + 10 s + trial, P95 = 2 RMSE, Max = 3 RMSE) through the
    study's table code: μ, σ per variant and scale, the paper's cells beside, the trend."""
    import pandas as pd

    from wheelload.studies.experiments import monte_carlo as mc

    rows = [
        {"variant": v.value, "s": s, "seed": i, "RMSE": 100 + 10 * s + i,
         "P95": 2 * (100 + 10 * s + i), "Max": 3 * (100 + 10 * s + i)}
        for v in mc.VARIANTS for s in mc.SCALES for i in (0, 1)
    ]  # fmt: skip
    table = mc.scale_table(pd.DataFrame(rows))
    cell = table.loc[(mc.VARIANTS[0].value, 4.0)]
    assert cell["RMSE μ"] == pytest.approx(140.5) and cell["RMSE σ"] == pytest.approx(0.5**0.5)
    shown = mc.side_by_side(table)
    assert shown.loc[16.0, "paper RMSE"] == "218.6 ± 11.14"
    assert shown.loc[16.0, f"{mc.LABELS[mc.VARIANTS[0]]} RMSE"] == "260.5 ± 0.71"
    words = mc.trend_words(table)
    # from s = 1 (110.5) to s = 16 (260.5): +135.7 %; the paper's 213.5 -> 218.6: +2.4 %
    assert "+135.7 % (paper +2.4 %) at 16" in words
