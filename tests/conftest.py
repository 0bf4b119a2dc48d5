import pytest

from wheelload.models import example_vehicle_path, load_vehicle


@pytest.fixture(scope="session")
def vehicle():
    return load_vehicle(example_vehicle_path())
