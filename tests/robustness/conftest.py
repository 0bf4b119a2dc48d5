"""Real logs for the robustness suite: the bundled example log and plant simulations."""

import shutil

import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.drive.scenario_log import write_log
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.experiments.faults.log_corruptions import SHORT_SCENARIOS
from wheelload.studies.pipeline.example_log import example_log_path


@pytest.fixture(scope="session")
def scenario_logs(tmp_path_factory):
    """Each short scenario simulated on the plant (sensor noise on), as a CSV log."""
    folder = tmp_path_factory.mktemp("scenarios")
    paths = {}
    for name in SHORT_SCENARIOS:
        result = run_scenario(name, example_vehicle_path())
        paths[name] = folder / f"{name}.csv"
        write_log(result.log, paths[name], result.metadata)
    return paths


@pytest.fixture
def user_files(tmp_path):
    """A user's log and vehicle file, copied into a fresh folder."""
    log = tmp_path / "drive.csv"
    vehicle = tmp_path / "car.toml"
    shutil.copy(example_log_path(), log)
    shutil.copy(example_vehicle_path(), vehicle)
    return log, vehicle
