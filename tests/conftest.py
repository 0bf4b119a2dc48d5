import pytest

from wheelload.models import example_vehicle_path, load_vehicle


@pytest.fixture(scope="session")
def vehicle():
    return load_vehicle(example_vehicle_path())


@pytest.fixture(scope="session")
def plant_log():
    """``plant_log(name)``: the measured log of a bundled scenario, simulated once per session."""
    from wheelload.estimators.logs.signals import signals_from_frame
    from wheelload.studies.drive.scenario_runner import run_scenario

    cache = {}

    def log(name):
        if name not in cache:
            result = run_scenario(name, example_vehicle_path())
            cache[name] = signals_from_frame(result.log, source=name)
        return cache[name]

    return log
