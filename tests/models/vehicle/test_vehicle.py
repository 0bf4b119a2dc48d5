"""Vehicle file: loading, validation messages that name the key, template."""

import dataclasses
import math
import tomllib

import pytest

from wheelload.models import (
    GRAVITY,
    VehicleFileError,
    example_vehicle_path,
    load_vehicle,
    static_loads,
    vehicle_from_dict,
    vehicle_template,
)
from wheelload.models.vehicle.plausibility import check_vehicle_ranges


def table():
    return tomllib.loads(example_vehicle_path().read_text())


def test_reference_vehicle_holds_table_one(vehicle):
    assert vehicle.mass.sprung == 1424.2
    assert (vehicle.geometry.lf, vehicle.geometry.lr) == (1.223, 1.527)
    assert vehicle.suspension.front.spring_rate == 60000.0
    assert vehicle.aero.lift_coefficient == 0.149
    # Damper coefficients are the Table I secants at 0.1 m/s (N / 0.1 m/s), to 0.1 N s/m.
    assert vehicle.suspension.front.damper_pull == pytest.approx(344.69 / 0.1, abs=0.1)


def test_static_loads_sum_to_weight_and_split_by_mass_centre(vehicle):
    loads = static_loads(vehicle)
    assert loads.sum() == pytest.approx(vehicle.mass.total * GRAVITY, rel=1e-12)
    assert loads[0] == loads[1] and loads[2] == loads[3]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: t["mass"].pop("sprung"), "missing key 'mass.sprung'"),
        (
            lambda t: t["suspension"]["front"].update(sprng_rate=1.0),
            "unknown key 'suspension.front.sprng_rate'",
        ),
        (lambda t: t.update(colour="red"), "unknown key 'colour'"),
        (lambda t: t["mass"].update(unsprung_rear=-99.0), "key 'mass.unsprung_rear'"),
        (lambda t: t["geometry"].update(lr=2.0), "key 'geometry.lf'"),
        (lambda t: t["mass"].update(total=2000.0), "key 'mass.total'"),
        (lambda t: t["mass"].update(total=1614.2), "key 'mass.total'"),  # 1 kg off the parts
        (lambda t: t["geometry"].update(imu_position=[0.1, 0.0]), "key 'geometry.imu_position'"),
        (lambda t: t["aero"].update(air_density="dense"), "key 'aero.air_density'"),
        (
            lambda t: t["filter"].update(constraint_noise_density=[1.0, 0.0, 1.0]),
            "key 'filter.constraint_noise_density'",
        ),
    ],
)
def test_invalid_files_are_rejected_naming_the_key(edit, message):
    data = table()
    edit(data)
    with pytest.raises(VehicleFileError, match=message.replace("[", r"\[")):
        vehicle_from_dict(data)


def test_error_names_the_file(tmp_path):
    path = tmp_path / "car.toml"
    path.write_text(example_vehicle_path().read_text().replace("sprung = 1424.2", ""))
    with pytest.raises(VehicleFileError, match=r"car\.toml: missing key 'mass.sprung'"):
        load_vehicle(path)


def test_template_is_a_valid_commented_vehicle_file(tmp_path):
    text = vehicle_template()
    assert text.count("#") > 40
    path = tmp_path / "template.toml"
    path.write_text(text)
    assert load_vehicle(path).name == "sports_car"


def _with_axle(vehicle, axle, **values):
    suspension = vehicle.suspension
    changed = dataclasses.replace(getattr(suspension, axle), **values)
    return dataclasses.replace(
        vehicle, suspension=dataclasses.replace(suspension, **{axle: changed})
    )


@pytest.mark.parametrize("axle", ["front", "rear"])
def test_spring_damper_and_bar_ranges_at_their_published_bounds(vehicle, axle):
    """The ranges of the suspension keys, 2 % inside and outside each bound, from the
    definitions by hand: ride frequency f = sqrt(k / m_c) / 2 pi within 0.5-5 Hz on the
    sprung corner mass m_c (lever rule: m_s l_r / L / 2 front, m_s l_f / L / 2 rear),
    damping ratio c / (2 sqrt(k m_c)) up to 3, the bar up to 10 times the spring."""
    g = vehicle.geometry
    lever = g.lr if axle == "front" else g.lf
    corner = vehicle.mass.sprung * lever / (g.lf + g.lr) / 2.0
    spring = getattr(vehicle.suspension, axle).spring_rate

    def flagged(name, **values):
        """Whether the key ``name`` is reported with ``values`` set on the axle."""
        changed = _with_axle(vehicle, axle, **values)
        return f"suspension.{axle}.{name}" in {v.key for v in check_vehicle_ranges(changed)}

    for hz, outside in ((0.49, True), (0.51, False), (4.9, False), (5.1, True)):
        rate = corner * (2.0 * math.pi * hz) ** 2
        assert flagged("spring_rate", spring_rate=rate) == outside, hz
    critical = 2.0 * math.sqrt(spring * corner)
    assert not flagged("damper_push", damper_push=2.94 * critical)
    assert flagged("damper_push", damper_push=3.06 * critical)
    assert not flagged("arb_rate", arb_rate=9.8 * spring)
    assert flagged("arb_rate", arb_rate=10.2 * spring)
