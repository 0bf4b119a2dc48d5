"""Many logs through the lean reader: long logs are read in chunks, not whole.

``run_logs`` sends a CSV or Parquet log over ``lean_bytes`` to the lean path
(``studies/pipeline/lean_estimate.py``); here ``lean_bytes=0`` sends every log there.
Tolerance: none for the written estimates (the lean path runs the same
compiled arithmetic as :meth:`TwoStageKF.run`, chunk by chunk: bit-identical);
1e-12 relative for the summary's means (sums in chunks, another order); the
batched whole-log path (side by side in the generated library) agrees with
it to 1e-9 relative.
"""

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import read_log
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.result import read_estimates
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.pipeline.batch import EstimateSettings, output_path, run_logs
from wheelload.studies.pipeline.example_log import example_log_path


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fleet")
    example = pd.read_csv(example_log_path())
    derived = example.drop(columns=["v_fl", "v_fr", "v_rl", "v_rr"])
    derived.loc[30:80, "d_fl"] = np.nan
    paths = [folder / "a.csv", folder / "b.parquet", folder / "c.csv"]
    example.to_csv(paths[0], index=False)
    derived.to_parquet(paths[1])
    example.iloc[200:].to_csv(paths[2], index=False)
    return paths


@pytest.mark.parametrize("workers", [1, 2])
def test_long_logs_in_a_fleet_are_read_in_chunks_and_equal_run(tmp_path, logs, workers):
    settings = EstimateSettings(vehicle=example_vehicle_path())
    lean_folder, whole_folder = tmp_path / "lean", tmp_path / "whole"
    lean_folder.mkdir()
    whole_folder.mkdir()
    lean = run_logs(logs, settings, lean_folder, workers=workers, progress=False, lean_bytes=0)
    whole = run_logs(logs, settings, whole_folder, workers=1, progress=False)
    assert (lean["error"] == "").all()
    kf = TwoStageKF(load_vehicle(example_vehicle_path()))
    for path in logs:
        expected = kf.run(read_log(path)).to_pandas()
        written = read_estimates(output_path(path, lean_folder))
        assert list(written.columns) == list(expected.columns)
        for column in expected.columns:
            assert np.array_equal(written[column].to_numpy(), expected[column].to_numpy()), column
    for column in ("samples", "skipped_samples", "negative_samples", "warnings"):
        assert list(lean[column]) == list(whole[column]), column
    assert list(lean["mode"]) == list(whole["mode"])
    for column in (
        "mean_fz_fl",
        "mean_fz_rr",
        "mean_std_fl",
        "min_fz",
        "rmse_pooled",
        "duration_s",
    ):
        np.testing.assert_allclose(lean[column], whole[column], rtol=1e-9, err_msg=column)
