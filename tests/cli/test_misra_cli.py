"""``wheelload misra``: the table per file and rule, before -> after, and its exit status."""

from __future__ import annotations

import json

import pytest

from wheelload.estimators.codegen.misra import cppcheck
from wheelload.studies.cli import main

pytestmark = pytest.mark.skipif(
    cppcheck() is None, reason="cppcheck not installed (apt-get install cppcheck)"
)

# Rule 10.3 (required): a double assigned to an int; rule 15.5 (advisory): two returns.
PLANTED = """int planted(double d);
int planted(double d)
{
    const int i = d;
    if (i > 0) {
        return 1;
    }
    return 0;
}
"""
FIXED = PLANTED.replace("const int i = d;", "const double i = d;").replace("i > 0", "i > 0.0")


def test_an_open_required_finding_fails_and_a_fix_shows_before_and_after(tmp_path, capsys):
    folder = tmp_path / "c"
    folder.mkdir()
    (folder / "planted.c").write_text(PLANTED)
    saved = tmp_path / "before.json"
    assert main(["misra", str(folder), "--save", str(saved)]) == 1
    out = capsys.readouterr().out
    assert "10.3" in out and "OPEN" in out and "1 open required findings" in out
    assert json.loads(saved.read_text())["findings"] == [["planted.c", 4, "10.3"],
                                                         ["planted.c", 6, "15.5"]]  # fmt: skip
    (folder / "planted.c").write_text(FIXED)
    assert main(["misra", str(folder), "--baseline", str(saved)]) == 0
    out = capsys.readouterr().out
    assert "1 -> 0" in out  # rule 10.3 fixed
    assert "0 open required findings" in out


def test_a_missing_folder_and_an_existing_save_are_one_line_errors(tmp_path, capsys):
    assert main(["misra", str(tmp_path / "absent")]) == 2
    assert "absent: no such folder or FMU" in capsys.readouterr().err
    (tmp_path / "old.json").write_text("{}")
    assert main(["misra", str(tmp_path), "--save", str(tmp_path / "old.json")]) == 2
    assert "old.json" in capsys.readouterr().err
