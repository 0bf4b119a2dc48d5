import dataclasses

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


def _fixed_mass(vehicle):
    payload = dataclasses.replace(vehicle.filter.payload, estimate=False)
    return vehicle.replace(filter=dataclasses.replace(vehicle.filter, payload=payload))


@pytest.fixture(scope="session")
def fixed_mass():
    """``fixed_mass(vehicle)``: ``vehicle`` with the payload filter off, its file's mass and CG
    held ([filter.payload] estimate = false). The independent reference filters, the RTS
    smoother's and the MHE's windows do not carry the payload filter
    (estimators/kf/payload.py, tested in tests/estimators/kf/test_payload.py)."""
    return _fixed_mass


@pytest.fixture(scope="session")
def fixed_vehicle():
    """The example vehicle with the payload filter off (see :func:`fixed_mass`)."""
    return _fixed_mass(load_vehicle(example_vehicle_path()))


def pytest_collection_modifyitems(items):
    """The test files in descending order of their ``heavy(seconds)`` mark (unmarked files:
    0 s, in collection order), each file's tests in their own order: with ``--dist loadfile
    --no-loadscope-reorder`` the longest files start first, so no worker is left with one
    at the end while the other waits (longest processing time first)."""
    seconds = {}
    for item in items:
        mark = item.get_closest_marker("heavy")
        seconds.setdefault(item.path, mark.args[0] if mark else 0.0)
    files = sorted(seconds, key=lambda path: -seconds[path])  # stable: ties keep their order
    rank = {path: k for k, path in enumerate(files)}
    items.sort(key=lambda item: rank[item.path])
