"""Many logs: the same bits however the logs are split; single runs within the stated tolerance.

The batched step (the generated library's C) and a single log's compiled loop
(the CasADi step's C) evaluate the same equations in another order of
operations, so they agree to a few units in the last place, not to the bit;
``BATCHED_TOLERANCE`` (1e-13 relative) states how far, and ``bench logs``
compares with it. How the logs are split among workers must change nothing.
"""

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import read_log
from wheelload.estimators.result import read_estimates
from wheelload.models import example_vehicle_path
from wheelload.studies.pipeline.batch import (
    BATCHED_TOLERANCE,
    EstimateSettings,
    _filter,
    expand_logs,
    output_path,
    process_logs,
)
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.summary_compare import compare

SETTINGS = EstimateSettings(vehicle=example_vehicle_path())


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    """Five 3 s windows of the bundled plant log, as CSV files."""
    source = pd.read_csv(example_log_path())
    folder = tmp_path_factory.mktemp("fleet")
    for k in range(5):
        source.iloc[200 * k : 200 * k + 300].to_csv(folder / f"log{k}.csv", index=False)
    return expand_logs([str(folder)])


def _loads(path, folder):
    frame = read_estimates(output_path(path, folder))  # CSV in round-trip form: exact
    wheels = ("fl", "fr", "rl", "rr")
    loads = frame[[f"fz_{w}" for w in wheels]].to_numpy()
    return loads, frame[[f"fz_std_{w}" for w in wheels]].to_numpy()


def test_a_log_alone_or_in_a_chunk_gives_the_same_bits_and_a_single_run_within_tolerance(
    fleet, tmp_path
):
    together, alone = tmp_path / "together", tmp_path / "alone"
    together.mkdir()
    alone.mkdir()
    rows = process_logs(fleet, SETTINGS, together)
    single_rows = [process_logs([path], SETTINGS, alone)[0] for path in fleet]
    assert rows == single_rows  # the summary, to the bit
    kf = _filter(SETTINGS.vehicle, False, None, False)
    for path in fleet:
        loads, std = _loads(path, together)
        np.testing.assert_array_equal(loads, _loads(path, alone)[0])
        expected = kf.run(read_log(path, wiring_checks=False))
        # a few ulps apart (module docstring): relative to the loads (about 5 kN)
        scale = np.abs(expected.loads).max()
        assert np.abs(loads - expected.loads).max() <= BATCHED_TOLERANCE * scale
        assert np.abs(std - expected.std).max() <= BATCHED_TOLERANCE * scale


def test_bench_compare_states_same_within_or_no():
    table = pd.DataFrame({"log": ["a", "b"], "mean_fz_fl": [4000.0, 4100.0], "mode": ["x", "x"]})
    assert compare(table, table.copy()) == ("same", 0.0)
    close = table.assign(mean_fz_fl=[4000.0 + 4e-10, 4100.0])
    verdict, difference = compare(close, table)
    assert verdict == "within" and difference == pytest.approx(4e-10, rel=1e-3)
    far = table.assign(mean_fz_fl=[4000.0 + 1e-6, 4100.0])  # 2.4e-10 relative: beyond
    assert compare(far, table)[0] == "NO"
    assert compare(table.assign(mode=["x", "y"]), table) == ("NO", float("inf"))


def test_a_chunk_runs_one_batch_at_a_time_as_read(fleet, monkeypatch):
    # Bounded memory: with batches of 2, the 5 logs go through the batched step as 2, 2, 1
    # (each batch run before the next is read), and the summary is the same to the bit.
    import wheelload.studies.pipeline.batch as batch

    expected = process_logs(fleet, SETTINGS, None)
    real, sizes = batch.run_batched, []

    def counted(kf, vehicle_path, logs):
        sizes.append(len(logs))
        return real(kf, vehicle_path, logs)

    monkeypatch.setattr(batch, "BATCH", 2)
    monkeypatch.setattr(batch, "run_batched", counted)
    assert process_logs(fleet, SETTINGS, None) == expected
    assert sizes == [2, 2, 1]
