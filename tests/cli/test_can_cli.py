"""``wheelload simulate ... --can DIR`` writes the CAN car's logs, which ``estimate`` reads
through the channel map it wrote; no file is written over without ``--force``."""

import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main

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
