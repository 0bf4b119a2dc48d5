"""AiM Race Studio and MoTeC i2 CSV exports (metadata and units rows above the channel names)
read through a channel map with each channel's unit from the export's units row.

The exports are written from the plant's ISO lane change in the layouts of
``estimators/logs/readers/logger_csv.py`` (AiM: key-value rows, an empty row, names,
units, an empty row, quoted data; MoTeC: key-value rows with a second column of keys,
two empty rows, names with a ``Distance`` channel, units, two empty rows). Read back,
they equal the SI log to the printed digits (6 significant).
"""

import csv

import numpy as np
import pytest

from wheelload.estimators.logs.readers import channel_names
from wheelload.estimators.logs.readers.logger_csv import logger_export
from wheelload.estimators.logs.signals import read_log
from wheelload.estimators.types import LogError
from wheelload.models.conventions import GRAVITY, WHEELS

#: our channel -> (export name, unit, factor from SI to that unit)
EXPORTED = {
    "ax": ("InlineAcc", "G", 1.0 / GRAVITY),
    "ay": ("LateralAcc", "G", 1.0 / GRAVITY),
    "az": ("VerticalAcc", "G", 1.0 / GRAVITY),
    "wx": ("RollRate", "deg/s", 180.0 / np.pi),
    "wy": ("PitchRate", "deg/s", 180.0 / np.pi),
    "wz": ("YawRate", "deg/s", 180.0 / np.pi),
    "vx": ("GPS Speed", "km/h", 3.6),
    **{f"d_{w}": (f"Damper {w.upper()}", "mm", 1000.0) for w in WHEELS},
}
AIM_METADATA = [
    ["Format", "AiM CSV File"], ["Venue", "Test Track"], ["Vehicle", "Sports car"],
    ["Racer", "Test"], ["Championship", ""], ["Date", "Saturday, May 4, 2024"],
    ["Time", "10:04:37"], ["Sample Rate", "100"], ["Duration", "13.530"],
    ["Segment", "Session"], ["Beacon Markers", "5.000"],
]  # fmt: skip
MOTEC_METADATA = """\
"Format","MoTeC CSV File",,,"Workbook",""
"Venue","Test Track",,,"Worksheet",""
"Vehicle","Sports car",,,"Vehicle Desc",""
"Driver","Test",,,"Engine ID",""
"Device","ADL3"
"Comment","",,,"Session","1"
"Log Date","04/05/2024",,,"Origin Time","0.000","s"
"Log Time","10:04:37",,,"Start Time","0.000","s"
"Sample Rate","100.000","Hz",,"End Time","13.530","s"
"Duration","13.530","s",,"Start Distance","0","m"
"Range","entire outing",,,"End Distance","0","m"
"Beacon Markers","5.000"


"""


@pytest.fixture(scope="module")
def dlc(plant_log):
    return plant_log("iso-dlc")


def _columns(dlc):
    frame = dlc.to_frame()
    return [(name, unit, frame[ours].to_numpy() * factor)
            for ours, (name, unit, factor) in EXPORTED.items()]  # fmt: skip


def write_aim(dlc, path):
    columns = _columns(dlc)
    with path.open("w", newline="", encoding="utf-8") as file:
        writer = csv.writer(file, quoting=csv.QUOTE_ALL)
        writer.writerows([*AIM_METADATA, []])
        writer.writerow(["Time", *(c[0] for c in columns)])
        writer.writerow(["s", *(c[1] for c in columns)])
        writer.writerow([])
        for k, t in enumerate(dlc.t):
            writer.writerow([f"{t:.3f}", *(f"{c[2][k]:.6g}" for c in columns)])


def write_motec(dlc, path):
    columns = _columns(dlc)
    distance = np.cumsum(dlc.vx) * 0.01
    with path.open("w", newline="", encoding="utf-8") as file:
        file.write(MOTEC_METADATA)
        writer = csv.writer(file, quoting=csv.QUOTE_ALL)
        writer.writerow(["Time", "Distance", *(c[0] for c in columns)])
        writer.writerow(["s", "m", *(c[1] for c in columns)])
        file.write("\n\n")
        for k, t in enumerate(dlc.t):
            writer.writerow(
                [f"{t:.3f}", f"{distance[k]:.2f}", *(f"{c[2][k]:.6g}" for c in columns)]
            )


def write_map(path, units: bool = False):
    lines = ["[clock]", 'channel = "ax"']
    for ours, (name, unit, _) in EXPORTED.items():
        lines += [f"[channels.{ours}]", f'source = "{name}"']
        lines += [f'unit = "{unit.lower() if unit == "G" else unit}"'] if units else []
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize(("writer", "program"), [(write_aim, "AiM"), (write_motec, "MoTeC")])
@pytest.mark.parametrize("units", [False, True], ids=["units from the export", "map units"])
def test_an_export_reads_as_the_si_log(dlc, tmp_path, writer, program, units):
    """Units from the units row (G, deg/s, km/h, mm) converted to SI; with the map's own
    units (``g`` for the export's ``G``: the same unit) the same. Tolerance: the export's 6
    significant digits (relative 1e-5 of each channel's range)."""
    path = tmp_path / "export.csv"
    writer(dlc, path)
    export = logger_export(path)
    assert export is not None and export.program.startswith(program)
    names = channel_names(path)
    assert {name for name, _, _ in EXPORTED.values()} <= set(names)
    assert "Format" not in names and "Time" not in names
    signals = read_log(path, channels=write_map(tmp_path / "map.toml", units))
    np.testing.assert_allclose(signals.t, dlc.t, rtol=0, atol=5e-4)
    for got, want in ((signals.acc, dlc.acc), (signals.rates, dlc.rates), (signals.d, dlc.d)):
        scale = np.max(np.abs(want), axis=0)
        np.testing.assert_allclose(got, want, rtol=0, atol=float(np.max(1e-5 * scale)))
    np.testing.assert_allclose(signals.vx, dlc.vx, rtol=1e-5)


def test_an_export_without_a_map_names_the_missing_channel(dlc, tmp_path):
    """Without a map the export's own names are not ours: one line asking for the map
    (before: the metadata's "Format" and "AiM CSV File" taken as channel names)."""
    path = tmp_path / "aim.csv"
    write_aim(dlc, path)
    with pytest.raises(LogError, match="no channel named 'ax'.*--channels") as error:
        read_log(path)
    assert "\n" not in str(error.value)


def test_a_map_unit_of_another_meaning_than_the_units_row_is_named(dlc, tmp_path):
    path = tmp_path / "aim.csv"
    write_aim(dlc, path)
    mapping = write_map(tmp_path / "map.toml")
    text = mapping.read_text().replace('source = "GPS Speed"', 'source = "GPS Speed"\nunit = "mph"')
    mapping.write_text(text)
    with pytest.raises(LogError, match="'GPS Speed' is declared in 'km/h' in the log but in 'mph'"):
        read_log(path, channels=mapping)


def test_a_semicolon_export_with_decimal_commas(dlc, tmp_path):
    """AiM's export in a locale with decimal commas: ``;`` between cells."""
    path = tmp_path / "aim.csv"
    write_aim(dlc, path)
    rows = list(csv.reader(path.read_text(encoding="utf-8").splitlines()))
    text = "\n".join(";".join(f'"{cell.replace(".", ",")}"' for cell in row) for row in rows)
    semicolon = tmp_path / "aim_semicolon.csv"
    semicolon.write_text(text + "\n", encoding="utf-8")
    signals = read_log(semicolon, channels=write_map(tmp_path / "map.toml"))
    np.testing.assert_allclose(signals.vx, dlc.vx, rtol=1e-5)


def test_a_plain_csv_is_not_an_export(dlc, tmp_path):
    path = tmp_path / "plain.csv"
    dlc.to_frame().to_csv(path, index=False)
    assert logger_export(path) is None
