"""The study report names the vehicle it ran on: in each study's Markdown, under every
table and in the line setting ours beside the paper's (a user's car is never set beside
Table II without its name)."""

import shutil

import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.experiments.catalog import model_line
from wheelload.studies.experiments.runs.context import Settings, model_caption

SUV = example_vehicle_path().with_name("suv.toml")


def test_the_report_lines_name_the_vehicle(tmp_path):
    mine = tmp_path / "my_van.toml"
    shutil.copy(SUV, mine)
    settings = Settings(vehicle_path=mine, vehicles_folder=SUV.parent)
    assert settings.vehicle_name == "suv"  # the file's name key, not the file's name
    assert model_line(settings).startswith(f"Vehicle: **suv** (`{mine}`).")
    assert model_caption(settings).startswith("*Vehicle:* **suv** (`my_van.toml`).")


@pytest.mark.heavy(12)
def test_a_study_on_a_users_car_names_it_in_its_report_and_summary(tmp_path, capsys):
    out = tmp_path / "study"
    argv = ["study", "cheon-structural", "--quick", "--out", str(out), "--vehicle", str(SUV)]
    assert main([*argv, "--no-progress", "--cache", str(tmp_path / "cache")]) == 0
    captured = capsys.readouterr()
    assert "study cheon-structural on vehicle 'suv':" in captured.out
    assert "bundled sports car" not in captured.err  # --vehicle given: nothing to say
    report = (out / "cheon-structural.md").read_text()
    assert report.startswith("Vehicle: **suv**") and "*Vehicle:* **suv** (`suv.toml`)" in report
