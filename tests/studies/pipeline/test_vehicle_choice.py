"""The vehicle a command runs on: ``--vehicle``, the bundled car for logs recorded on it,
and a user's log without ``--vehicle`` refused with the fix."""

import json
import shutil

import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.vehicle_choice import (
    bundled_line,
    bundled_name,
    from_bundled_car,
    vehicle_for_logs,
)


def test_the_bundled_car_is_named_from_its_file():
    assert bundled_name() == "sports_car"
    line = bundled_line("simulate")
    assert "bundled sports car 'sports_car'" in line and str(example_vehicle_path()) in line
    assert "--vehicle FILE" in line


def test_the_example_log_and_a_log_simulated_on_the_bundled_car_need_no_vehicle(tmp_path):
    assert vehicle_for_logs(None, [example_log_path()], "sensor-sets") == example_vehicle_path()
    log = tmp_path / "sim.csv"
    shutil.copy(example_log_path(), log)
    (tmp_path / "sim.csv.meta.json").write_text(json.dumps({"vehicle": "sports_car"}))
    assert from_bundled_car(log)
    (tmp_path / "sim.csv.meta.json").write_text(json.dumps({"vehicle": "suv"}))
    assert not from_bundled_car(log)  # simulated on another car


def test_a_users_log_without_vehicle_is_refused_with_the_fix(tmp_path):
    log = tmp_path / "mine.csv"
    shutil.copy(example_log_path(), log)  # the same numbers, but nothing says which car
    with pytest.raises(ValueError, match="give --vehicle FILE") as error:
        vehicle_for_logs(None, [example_log_path(), log], "study")
    message = str(error.value)
    assert message.startswith(str(log)) and "\n" not in message
    assert "bundled sports car, not meant for your log" in message
    vehicle = tmp_path / "car.toml"
    shutil.copy(example_vehicle_path(), vehicle)
    assert vehicle_for_logs(str(vehicle), [log], "study") == vehicle


def test_a_missing_vehicle_file_is_one_line():
    with pytest.raises(ValueError, match=r"nope.toml: no such vehicle file \(--vehicle\)"):
        vehicle_for_logs("nope.toml", [example_log_path()], "study")
