"""``wheelload simulate ... --can DIR`` writes the CAN car's logs, which ``estimate`` reads
through the channel map it wrote; no file is written over without ``--force``."""

import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.drive.can_car import LATENCIES, UNION_CLOCK, channel_map_text

pytestmark = pytest.mark.heavy(15)  # seconds (tests/conftest.py)


def test_simulate_writes_the_can_logs_that_estimate_reads(tmp_path, capsys):
    can = tmp_path / "can"
    can.mkdir()
    args = ["simulate", "iso-dlc", "--rate", "200", "--out", str(tmp_path / "dlc.csv"),
            "--can", str(can)]  # fmt: skip
    assert main(args) == 0
    names = sorted(path.name for path in can.iterdir())
    assert names == ["dlc.blf", "dlc.dbc", "dlc.latency.toml", "dlc.mf4", "dlc.toml"]
    capsys.readouterr()
    for written in ("dlc.csv", "dlc.csv.meta.json"):  # only the CAN files left to refuse
        (tmp_path / written).unlink()
    assert main(args) != 0
    error = capsys.readouterr().err
    assert "exists: choose another name or give --force" in error and "dlc.mf4" in error
    for log in ("dlc.mf4", "dlc.blf"):
        estimate = ["estimate", str(can / log), "--vehicle", str(example_vehicle_path()),
                    "--channels", str(can / "dlc.latency.toml")]  # fmt: skip
        assert main(estimate) == 0
        out = capsys.readouterr().out
        pooled = float(next(line for line in out.splitlines() if "POOLED" in line).split()[1])
        assert pooled < 30.0  # N against the log's own 50 Hz transducer loads (19.8 measured)


def test_estimate_runs_a_union_table_and_scores_each_wheel_at_its_own_frames(tmp_path, capsys):
    """``[clock] union``: every channel at its own stamps (a transducer frame carries one
    corner, each wheel's reference interpolated onto every row to be scored); the jittered
    CAN car's lane change within 30 N (about 25 N measured; 1.63x the latency map's and
    refused with jitter before)."""
    can = tmp_path / "can"
    can.mkdir()
    assert main(["simulate", "iso-dlc", "--rate", "200", "--out", str(tmp_path / "dlc.csv"),
                 "--can", str(can)]) == 0  # fmt: skip
    (can / "dlc.union.toml").write_text(channel_map_text("dlc.dbc", LATENCIES, UNION_CLOCK))
    capsys.readouterr()
    estimate = ["estimate", str(can / "dlc.mf4"), "--vehicle", str(example_vehicle_path()),
                "--channels", str(can / "dlc.union.toml")]  # fmt: skip
    assert main(estimate) == 0
    out = capsys.readouterr().out
    pooled = float(next(line for line in out.splitlines() if "POOLED" in line).split()[1])
    assert pooled < 30.0
