"""The console command on real files."""

import numpy as np
import pandas as pd
import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main


def test_estimate_on_the_bundled_example(tmp_path, capsys):
    out, plot = tmp_path / "estimates.csv", tmp_path / "estimates.png"
    assert main(["estimate", "--example", "--out", str(out), "--plot", str(plot)]) == 0
    text = capsys.readouterr().out
    assert "POOLED" in text and "RMSE" in text
    estimates = pd.read_csv(out)
    assert len(estimates) == 1353
    assert np.isfinite(estimates.to_numpy()).all()
    assert {"fz_fl", "fz_std_rr", "residual_roll", "status"} <= set(estimates.columns)
    assert plot.stat().st_size > 20_000


def test_estimate_reports_a_bad_vehicle_file(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(example_vehicle_path().read_text().replace("total = 1613.2", "total = -5.0"))
    assert main(["estimate", "--example", "--vehicle", str(bad)]) == 2
    assert "key 'mass.total'" in capsys.readouterr().err


def test_estimate_reports_a_missing_log(tmp_path, capsys):
    code = main(["estimate", str(tmp_path / "nope.csv"), "--vehicle", str(example_vehicle_path())])
    assert code == 2
    assert "nope.csv: no such log file" in capsys.readouterr().err


def test_vehicle_template_round_trips(tmp_path, capsys):
    assert main(["vehicle", "--template"]) == 0
    path = tmp_path / "mine.toml"
    path.write_text(capsys.readouterr().out)
    assert main(["vehicle", str(path)]) == 0
    assert "static loads" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [["estimate"], ["estimate", "x.csv"]])
def test_estimate_without_inputs_is_an_error(argv, capsys):
    assert main(argv) == 2
    assert "--vehicle" in capsys.readouterr().err
