"""The geometric-transfer term on a plant without link geometry (roll centres 0, anti-pitch 0).

With the file as the car (no links), the term keeps only its body-tilt part (the
springs carry the body-z force): on the lane change, MTi-1 grade, 100 Hz, seed 0,
method D's pooled RMSE is 27.4 N with it and 35.5 N without (the link couples
themselves are zero). Tolerance: the term must not cost D more than 2 % (the
sensor-errors study's "neutral").
"""

from __future__ import annotations

import tempfile
import tomllib
from pathlib import Path

import numpy as np

from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models import example_vehicle_path
from wheelload.models.vehicle.description import vehicle_from_dict
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.experiments.runs.vehicle_variants import Edit, Variant
from wheelload.studies.metrics import pooled_metrics

KEYS = ("roll_centre_height", "anti_pitch_brake", "anti_pitch_drive")


def _without_links(text: str) -> str:
    edits = tuple(Edit(table=f"suspension.{axle}", key=key, value=0.0)
                  for axle in ("front", "rear") for key in KEYS)  # fmt: skip
    return Variant(label="no links", edits=edits).apply(text)


def _term_off(text: str) -> str:
    edit = Edit(table="model", key="geometric_transfer", value=False)
    return Variant(label="off", edits=(edit,)).apply(text)


def test_the_term_helps_method_d_on_a_plant_without_link_geometry():
    text = _without_links(example_vehicle_path().read_text(encoding="utf-8"))
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "no_links.toml"
        path.write_text(text, encoding="utf-8")
        log = run_scenario("iso-dlc", path, options=Options()).log
    signals = signals_from_frame(log, wiring_checks=False)
    scores = {}
    for label, variant in (("on", text), ("off", _term_off(text))):
        loads = build("D", vehicle_from_dict(tomllib.loads(variant))).run(signals).loads
        scores[label] = pooled_metrics(loads, signals.reference)["RMSE"]
    assert scores["on"] <= 1.02 * scores["off"], scores
    assert np.isfinite(list(scores.values())).all()
