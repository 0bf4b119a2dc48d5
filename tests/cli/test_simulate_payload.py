"""``wheelload simulate --payload`` and ``--payload-change`` on real files."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from wheelload.models import GRAVITY, example_vehicle_path, load_vehicle, static_loads
from wheelload.studies.cli import main

LOADS = ["fz_fl", "fz_fr", "fz_rl", "fz_rr"]
TRAVEL = ["d_fl", "d_fr", "d_rl", "d_rr"]


def test_payload_is_carried_by_the_plant_and_recorded(tmp_path, capsys):
    out = tmp_path / "loaded.csv"
    assert main(["simulate", "standstill", "--out", str(out), "--payload", "150,-1.3,0,0.15"]) == 0
    log = pd.read_csv(out)
    vehicle = load_vehicle(example_vehicle_path())
    end = log[log["t"] > 4.0]
    # the reference loads carry the payload's weight (0.1 %, sensor-free reference) ...
    total = end[LOADS].sum(axis=1).to_numpy()
    np.testing.assert_allclose(total, (vehicle.mass.total + 150.0) * GRAVITY, rtol=1e-3)
    # ... mostly on the rear axle (it sits 1.3 m behind the sprung CG), and travel is
    # measured from the file's reference state: the rear springs are compressed by mm
    extra = end[LOADS].mean().to_numpy() - static_loads(vehicle)
    assert extra[2] > 5 * extra[0] > 0
    assert end[["d_rl", "d_rr"]].mean().min() > 5e-3
    metadata = json.loads(out.with_name(out.name + ".meta.json").read_text())
    assert metadata["payload"]["initial"] == {"mass": 150.0, "x": -1.3, "y": 0.0, "z": 0.15}
    assert metadata["payload"]["change"] is None


def test_payload_change_at_a_stop_is_recorded(tmp_path):
    out = tmp_path / "change.parquet"
    code = main(["simulate", "standstill", "--out", str(out), "--noise", "0",
                 "--payload-change", "1,80,-0.1,-0.37,0.1"])  # fmt: skip
    assert code == 0
    log = pd.read_parquet(out)
    total = log[LOADS].sum(axis=1).to_numpy()
    t = log["t"].to_numpy()
    weight = load_vehicle(example_vehicle_path()).mass.total * GRAVITY
    assert total[t < 0.9].mean() == pytest.approx(weight, rel=1e-3)
    assert total[t > 3.0].mean() == pytest.approx(weight + 80.0 * GRAVITY, rel=1e-3)
    metadata = json.loads(out.with_name(out.name + ".meta.json").read_text())
    assert metadata["payload"]["change"]["time"] == 1.0
    assert metadata["payload"]["change"]["payload"]["mass"] == 80.0


def test_an_existing_log_is_kept_without_force(tmp_path, capsys):
    out = tmp_path / "kept.csv"
    out.write_text("precious\n")
    assert main(["simulate", "standstill", "--out", str(out), "--payload", "150"]) == 2
    assert "--force" in capsys.readouterr().err
    assert out.read_text() == "precious\n"
    assert main(["simulate", "standstill", "--out", str(out), "--payload", "150", "--force"]) == 0
    assert len(pd.read_csv(out)) == 500


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--payload", "abc", "--payload 'abc': not numbers; --payload expects KG[,X,Y,Z]"),
        ("--payload", "150,0.3", "--payload '150,0.3': 2 values; --payload expects KG[,X,Y,Z]"),
        ("--payload", "-5", "--payload '-5': payload 'mass' must be >= 0 kg"),
        ("--payload", "150,nan,0,0", "payload 'x' must be finite"),
        ("--payload-change", "5", "--payload-change '5': no payload after the time"),
        ("--payload-change", "x,80", "time 'x' is not a number; --payload-change expects T,KG"),
        ("--payload-change", "-1,80", "payload change time must be >= 0 s"),
    ],
)
def test_malformed_payload_is_a_one_line_error(tmp_path, capsys, option, value, message):
    out = tmp_path / "bad.csv"
    assert main(["simulate", "standstill", "--out", str(out), f"{option}={value}"]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


def test_a_change_while_the_car_drives_is_refused(tmp_path, capsys):
    out = tmp_path / "dlc.csv"
    assert main(["simulate", "iso-dlc", "--out", str(out), "--payload-change", "5,80"]) == 2
    err = capsys.readouterr().err
    assert "never stands still here: use the standstill or stop-and-go scenario" in err
    assert main(["simulate", "stop-and-go", "--out", str(out), "--payload-change", "9,80"]) == 2
    assert "choose a change time <= 8.5 s" in capsys.readouterr().err
    assert not out.exists()
