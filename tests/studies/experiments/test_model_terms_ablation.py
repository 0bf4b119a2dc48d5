"""``wheelload ablation`` end to end on one scenario, scored against the plant's loads."""

import pandas as pd

from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.cli import main
from wheelload.studies.experiments.model_terms_ablation import configurations


def test_ablation_on_the_bounce_sweep_credits_the_stops(tmp_path, capsys):
    out = tmp_path / "ablation.csv"
    argv = ["ablation", "--vehicle", str(example_vehicle_path()), "--scenario", "bounce-sweep",
            "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    table = pd.read_csv(out).set_index("configuration")
    assert set(table.index) == set(configurations(load_vehicle(example_vehicle_path())))
    assert table[["rmse", "max"]].notna().all().all()
    # The sweep drives the suspension into its bump stops and the body into
    # pitch and roll accelerations. Measured (seed 0): paper 350 N, all terms
    # 67 N, all but the stops 116 N, the stops alone 329 N.
    assert table.loc["all", "rmse"] < 0.35 * table.loc["paper", "rmse"]
    assert table.loc["all", "rmse"] < 0.8 * table.loc["-stops", "rmse"]
    assert table.loc["+stops", "rmse"] < table.loc["paper", "rmse"]
    assert "+stops" in capsys.readouterr().out
    assert main(argv) == 2  # an existing --out is not overwritten without --force
    assert "exists" in capsys.readouterr().err
