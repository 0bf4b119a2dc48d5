"""Vehicle file: loading, validation messages that name the key, template."""

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
