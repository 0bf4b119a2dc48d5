"""Item 5: absurd vehicle files are refused naming the key and the accepted interval."""

import re

import pytest

from wheelload.models import example_vehicle_path, load_vehicle, vehicle_template
from wheelload.models.vehicle.plausibility import RANGES, check_vehicle_ranges, vehicle_keys
from wheelload.studies.cli import build_parser, main

#: The issue's absurd files: (replacement in the bundled file, the key the error names).
ABSURD = {
    "cg height 10 m": ("cg_height = 0.497", "cg_height = 10.0", "geometry.cg_height"),
    "lf = 1e-9": ("lf = 1.223\nlr = 1.527", "lf = 1e-9\nlr = 2.8", "geometry.lf"),
    "total mass 3 g": (
        "sprung = 1424.2",
        "sprung = 0.002",
        "mass.total",
    ),
    "lift coefficient -50": (
        "lift_coefficient = 0.149",
        "lift_coefficient = -50.0",
        "aero.lift_coefficient",
    ),
    "ARB ratio 1e9": ("arb_ratio = 1.0", "arb_ratio = 1e9", "suspension.front.arb_ratio"),
    "track 1e-9": ("track_front = 1.632", "track_front = 1e-9", "geometry.track_front"),
    "initial_std 1.2e6": ("initial_std = 1000.0", "initial_std = 1.2e6", "filter.initial_std"),
    "initial_std 1e200": ("initial_std = 1000.0", "initial_std = 1e200", "filter.initial_std"),
    "process noise 1e300": (
        "process_noise_density = 2.25e7",
        "process_noise_density = 1e300",
        "filter.process_noise_density",
    ),
}


def absurd_file(tmp_path, case):
    old, new, _ = ABSURD[case]
    text = example_vehicle_path().read_text()
    assert old in text
    text = text.replace(old, new, 1)
    if case == "total mass 3 g":
        text = re.sub(r"unsprung_front = [0-9.]+", "unsprung_front = 0.0005", text)
        text = re.sub(r"unsprung_rear = [0-9.]+", "unsprung_rear = 0.0005", text)
        text = re.sub(r"\ntotal = [0-9.]+", "\ntotal = 0.003", text)
    path = tmp_path / "absurd.toml"
    path.write_text(text)
    return path


def test_every_vehicle_file_key_has_a_range():
    """A key added to the vehicle file without a range here fails this test."""
    assert set(vehicle_keys()) == set(RANGES)


def test_the_bundled_vehicle_and_the_template_pass(tmp_path, capsys):
    assert check_vehicle_ranges(load_vehicle(example_vehicle_path())) == []
    template = tmp_path / "template.toml"
    template.write_text(vehicle_template())
    assert main(["vehicle", str(template)]) == 0
    assert "valid vehicle" in capsys.readouterr().out


@pytest.mark.parametrize("case", sorted(ABSURD))
def test_an_absurd_vehicle_is_refused_with_the_interval(tmp_path, capsys, case):
    path = absurd_file(tmp_path, case)
    assert main(["vehicle", str(path)]) == 2
    err = capsys.readouterr().err
    key = ABSURD[case][2]
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"key '{key}'" in err, err
    assert re.search(rf"key '{re.escape(key)}' = \S+ is outside the accepted \[\S+, \S+\]", err)
    assert "--allow-unusual" in err


def test_allow_unusual_accepts_a_special_vehicle(tmp_path, capsys):
    path = absurd_file(tmp_path, "cg height 10 m")
    assert main(["vehicle", str(path), "--allow-unusual"]) == 0
    assert "valid vehicle" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv",
    [
        ["estimate", "--example"],
        ["simulate", "iso-dlc", "--out", "x.csv"],
        ["codegen", "--out", "x"],
        ["vehicle", "car.toml"],
        ["bench", "kf"],
        ["bench", "codegen"],
        ["bench", "mhe"],
        ["study", "mhe-vs-kf"],
    ],
)
def test_every_command_that_reads_a_vehicle_takes_allow_unusual(argv):
    assert build_parser().parse_args([*argv, "--allow-unusual"]).allow_unusual is True


def test_estimate_refuses_an_absurd_vehicle_before_reading_the_log(tmp_path, capsys):
    path = absurd_file(tmp_path, "ARB ratio 1e9")
    assert main(["estimate", "--example", "--vehicle", str(path)]) == 2
    assert "suspension.front.arb_ratio' = 1e+09" in capsys.readouterr().err
