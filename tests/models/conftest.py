"""Fixtures of the model tests: the example vehicle's model parameters."""

import pytest

from wheelload.models import ModelParameters


@pytest.fixture(scope="module")
def p(vehicle):
    """The example vehicle's :class:`ModelParameters` (the models' numeric parameter input)."""
    return ModelParameters.from_vehicle(vehicle)
