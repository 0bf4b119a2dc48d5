"""``compare``, ``sensor-sets`` and ``tune`` on logs with part of the references or without az,
written to disk from the plant's lane change: results and one-line notes, no traceback.

Before, ``compare`` on front references only stopped with ``KeyError: 'rl'``,
``sensor-sets`` without az with ``KeyError: "['az'] not found"``, and ``tune`` with front
references only with "no logs with reference loads" after its whole fit.
"""

import numpy as np
import pandas as pd
import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main

VEHICLE = str(example_vehicle_path())


@pytest.fixture(scope="module")
def frame(plant_log):
    return plant_log("iso-dlc").to_frame()


@pytest.fixture
def front_only(frame, tmp_path):
    path = tmp_path / "front_only.csv"
    frame.drop(columns=["fz_rl", "fz_rr"]).to_csv(path, index=False)
    return path


def test_compare_scores_the_wheels_with_a_reference_and_names_the_others(
    frame, front_only, tmp_path, capsys
):
    """FL and FR score as in the full log's table (to 1e-9 N), pooled is over them alone,
    RL and RR are '-' with a note naming them; figures only for FL and FR."""
    table = tmp_path / "table.csv"
    figures = tmp_path / "figures"
    args = ["compare", str(front_only), "--vehicle", VEHICLE, "--methods", "kf", "--repeat", "1"]
    assert main([*args, "--csv", str(table), "--figures", str(figures)]) == 0
    out = capsys.readouterr().out
    assert "note: not scored: RL RR" in out
    rmse_line = next(line for line in out.splitlines() if line.startswith("RMSE [N]"))
    assert rmse_line.split()[-3:-1] == ["-", "-"]
    written = pd.read_csv(table)
    assert set(written["wheel"]) == {"fl", "fr", "pooled"}
    assert sorted(p.name for p in figures.iterdir()) == [
        "front_only_compare_fl.png",
        "front_only_compare_fr.png",
    ]
    full = tmp_path / "full.csv"
    frame.to_csv(full, index=False)
    assert main(["compare", str(full), "--vehicle", VEHICLE, "--methods", "kf", "--repeat", "1",
                 "--csv", str(tmp_path / "full_table.csv")]) == 0  # fmt: skip
    whole = pd.read_csv(tmp_path / "full_table.csv").set_index("wheel")
    scored = written.set_index("wheel")
    for wheel in ("fl", "fr"):
        assert scored.loc[wheel, "RMSE"] == pytest.approx(whole.loc[wheel, "RMSE"], abs=1e-9)
    # pooled over FL and FR: the root of the mean of their squares (equal sample counts)
    pooled = np.sqrt(np.mean(np.square(whole.loc[["fl", "fr"], "RMSE"])))
    assert scored.loc["pooled", "RMSE"] == pytest.approx(pooled, rel=1e-9)


def test_sensor_sets_without_az_assumes_it_and_says_so(frame, tmp_path, capsys):
    path = tmp_path / "no_az.csv"
    frame.drop(columns=["az"]).to_csv(path, index=False)
    assert main(["sensor-sets", str(path), "--vehicle", VEHICLE, "--splits", "0.4"]) == 0
    out = capsys.readouterr().out
    assert "note: the log has no az: every mode assumes az = g" in out
    rows = [line for line in out.splitlines() if line.strip().startswith(("full", "no az"))]
    assert len(rows) == 2
    # "full" and "no az" are the same run on this log: the same RMSE
    assert rows[0].split()[-4] == rows[1].split()[-4]


@pytest.mark.heavy(60)
def test_tune_on_front_references_says_so_up_front_and_calibrates_on_them(
    front_only, tmp_path, capsys
):
    """A short fit (3 iterations): the note names RL RR before the fit, and the reported
    sigma is calibrated on FL and FR (its coverage line printed, the file written)."""
    out = tmp_path / "tuned.toml"
    args = ["tune", str(front_only), "--vehicle", VEHICLE, "--out", str(out)]
    assert main([*args, "--iterations", "3"]) == 0
    captured = capsys.readouterr()
    assert "reference loads on FL FR only: RL RR not scored" in captured.err
    assert "reported sigma calibrated on the tuning logs" in captured.out
    assert out.exists()
