"""The derived model parameters: one Function gives them, its sources are all that moves them.

The generated C recomputes a derived parameter when one of its sources is set at run time
(tests/estimators/codegen/test_codegen_derived.py); these tests pin what that relies on:
a vehicle-file change of a source moves no parameter but itself and the parameters derived
from it, and those to the values of ``derived_function`` (to the bit: the parameters take
them from it); a mass-centre input moves more, which is why the C refuses it.
"""

import dataclasses

import numpy as np
import pytest

from wheelload.models import ModelParameters
from wheelload.models.parameters import (
    AXLE_KEYS,
    DERIVED,
    MASS_CENTRE_INPUTS,
    derived_function,
    derived_sources,
)

NAMES = ModelParameters.names()


def moved(vehicle, changed) -> set[str]:
    before = ModelParameters.from_vehicle(vehicle).vector()
    after = ModelParameters.from_vehicle(changed).vector()
    return {NAMES[k] for k in np.nonzero(before != after)[0]}


def test_the_parameters_take_their_derived_values_from_the_function(vehicle):
    p = ModelParameters.from_vehicle(vehicle)
    derived = derived_function()(p.vector()).full().ravel()
    assert list(derived) == [getattr(p, name) for name in DERIVED]
    assert all(type(getattr(p, name)) is float for name in DERIVED)


@pytest.mark.parametrize("axle", ["front", "rear"])
@pytest.mark.parametrize("name", list(AXLE_KEYS))
def test_a_source_in_the_file_moves_itself_and_what_derives_from_it(vehicle, axle, name):
    key = AXLE_KEYS[name]
    section = getattr(vehicle.suspension, axle)
    value = getattr(section, key)
    section = dataclasses.replace(section, **{key: value * 1.1 + 0.01})
    changed = vehicle.replace(suspension=dataclasses.replace(vehicle.suspension, **{axle: section}))
    field = f"{name}_{axle}"
    followers = {d for d, sources in derived_sources().items() if field in sources}
    assert {field} <= moved(vehicle, changed) <= {field} | followers


def test_springs_and_bars_feed_the_split_and_mass_and_cg_the_static_loads():
    sources = derived_sources()
    assert {"spring_front", "spring_rear", "arb_rate_front", "arb_ratio_rear",
            "term_geometric_transfer"} <= set(sources["roll_split_front"])  # fmt: skip
    assert all(sources[f"static_{w}"] == ("mass", "lf", "lr") for w in ("fl", "fr", "rl", "rr"))
    assert not set(DERIVED) & {s for found in sources.values() for s in found}


@pytest.mark.parametrize("key", ["sprung", "unsprung_front", "unsprung_rear"])
def test_a_mass_centre_input_moves_parameters_beyond_the_derived_ones(vehicle, key):
    mass = vehicle.mass
    total = mass.total + 10.0
    changed = vehicle.replace(
        mass=dataclasses.replace(mass, **{key: getattr(mass, key) + 10.0, "total": total})
    )
    found = moved(vehicle, changed)
    field = {"sprung": "sprung_mass"}.get(key, key)
    assert field in MASS_CENTRE_INPUTS
    # the whole-vehicle CG moves with file values that are not parameters
    assert {"mass", "lf", "lr", "cg_height"} <= found
