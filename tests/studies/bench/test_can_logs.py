"""The KF on the CAN car's logs (``wheelload bench can``): real MDF4 bus logging and BLF
files of the plant's lane change at 200 Hz, read through the CAN car's channel maps.

Stated by issue 40: with the frames' latency keys, the KF's RMSE within 1.05x of the
synchronous 200 Hz log's (measured 0.945x: the 100 Hz travel interpolated onto the IMU's
clock); ``ay`` delayed 0.3 s inside the IMU is found by the wiring checks within 0.05 s
(measured +0.018 s: the lateral-velocity rate, not logged, leads vx wz), and the lag
added to ``ay``'s latency key brings the RMSE back within 1.05x (measured 1.010x).
"""

import math

import pytest

from wheelload.studies.bench.can_logs import can_study, with_latency

pytestmark = pytest.mark.heavy(20)  # seconds (tests/conftest.py)

DELAY = 0.3  # s
RATIO = 1.05
LAG_TOLERANCE = 0.05  # s


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    rows, lag = can_study(tmp_path_factory.mktemp("can"), delay=DELAY)
    return {(row.log, row.channel_map): row for row in rows}, lag


@pytest.mark.parametrize("log", ["can.mf4", "can.blf", "rough.mf4", "rough.blf"])
def test_can_logs_with_latency_keys_score_as_the_synchronous_log(study, log):
    """Also with a 0.2 ms jitter (``rough``), on the maps' even 200 Hz clock."""
    rows, _ = study
    assert rows[(log, f"{log.split('.')[0]}.latency.toml")].ratio < RATIO


@pytest.mark.parametrize(("log", "ratio"), [("still.mf4", 1.15), ("can.mf4", 1.3)])
def test_union_tables_run_each_row_at_its_own_time_stamp(study, log, ratio):
    """``[clock] union``: the travel at its own 100 Hz stamps, each row filtered at its own
    time (measured 1.077x without jitter, 1.208x with: an IMU row holds the travel of up
    to 10 ms before it, where the even clock interpolates the next travel sample onto it);
    before, 1.63x and refused."""
    rows, _ = study
    row = rows[(log, f"{log.split('.')[0]}.union.toml")]
    assert row.note == "" and row.ratio < ratio


def test_hidden_ay_delay_is_found_and_the_latency_key_restores_the_rmse(study):
    rows, lag = study
    assert abs(lag - DELAY) < LAG_TOLERANCE
    assert rows[("late.mf4", "late.latency.toml")].ratio > 2.0  # the delay does harm
    for log in ("late.mf4", "late.blf"):
        assert rows[(log, "late.fixed.toml")].ratio < RATIO


def test_latency_is_added_to_the_named_channel_only():
    text = '[channels.ax]\nsource = "AccX"\nlatency = 0.006\n\n[channels.ay]\nsource = "AccY"\n' \
        'unit = "m/s^2"\nlatency = 0.006\n'  # fmt: skip
    edited = with_latency(text, "ay", 0.3)
    assert "latency = 0.306" in edited and edited.count("latency = 0.006") == 1
    with pytest.raises(ValueError, match="no latency key for 'wz'"):
        with_latency(text, "wz", 0.3)
    assert math.isclose(float(edited.rsplit("= ", 1)[1]), 0.306)
