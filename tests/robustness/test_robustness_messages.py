"""Item 7: every error a user can cause is one line naming the file and the fix."""

import os
from pathlib import Path

import pytest

from wheelload.studies.cli import main


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def test_output_into_a_missing_folder(user_files, capsys, tmp_path):
    log, vehicle = user_files
    out = tmp_path / "no" / "such" / "loads.csv"
    assert main(["estimate", str(log), "--vehicle", str(vehicle), "--out", str(out)]) == 2
    assert f"folder '{out.parent}' does not exist" in one_line_error(capsys)


def read_only_folder(tmp_path) -> Path:
    """A folder this process cannot create files in (root ignores permission bits)."""
    if os.geteuid() == 0:
        return Path("/proc")
    folder = tmp_path / "locked"
    folder.mkdir(mode=0o555)
    return folder


@pytest.mark.parametrize("option", ["--out", "--plot"])
def test_output_into_a_read_only_folder(user_files, capsys, tmp_path, option):
    log, vehicle = user_files
    out = read_only_folder(tmp_path) / ("loads.csv" if option == "--out" else "loads.png")
    assert main(["estimate", str(log), "--vehicle", str(vehicle), option, str(out)]) == 2
    assert "cannot write in folder" in one_line_error(capsys)


def test_a_log_that_is_not_utf8_is_named(user_files, capsys):
    log, vehicle = user_files
    data = log.read_bytes().replace(b"t,vx", b"t\xff\xfe,vx", 1)
    log.write_bytes(data)
    assert main(["estimate", str(log), "--vehicle", str(vehicle)]) == 2
    err = one_line_error(capsys)
    assert f"{log}: is not UTF-8 text" in err and "save the log as UTF-8" in err


def test_a_vehicle_file_that_is_not_utf8_is_named(user_files, capsys):
    log, vehicle = user_files
    vehicle.write_bytes(vehicle.read_bytes().replace(b"sports_car", b"sp\xe9rts_car", 1))
    assert main(["vehicle", str(vehicle)]) == 2
    err = one_line_error(capsys)
    assert f"{vehicle}: is not UTF-8 text" in err and "save the vehicle file as UTF-8" in err


def test_a_folder_given_as_vehicle_file(tmp_path, capsys):
    assert main(["vehicle", str(tmp_path)]) == 2
    assert "is a folder" in one_line_error(capsys)
