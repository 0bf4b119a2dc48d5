"""The vehicle-file text writer: values replaced, every other line and comment kept."""

import pytest

from wheelload.models.vehicle.file import (
    add_values,
    edited_vehicle_text,
    example_vehicle_path,
    load_vehicle,
    replace_values,
    set_values,
    write_vehicle_text,
)


def test_text_edit_keeps_comments_and_names_a_missing_key():
    text = "[mass]\nsprung = 1.0   # kg\n[geometry]\nlf = 2.0\n"
    edited = edited_vehicle_text(text, {("mass", "sprung"): 3.5, ("geometry", "lf"): 1.25})
    assert edited == "[mass]\nsprung = 3.5   # kg\n[geometry]\nlf = 1.25\n"
    with pytest.raises(ValueError, match="geometry.lr"):
        edited_vehicle_text(text, {("geometry", "lr"): 1.0})


def test_set_values_keeps_the_old_comment_above_and_add_values_appends_a_missing_key():
    text = "[mass]\nsprung = 1.0   # kg\n[geometry]\nlf = 2.0\n"
    edited = set_values(text, {("mass", "sprung"): (3.5, "weighed")})
    assert edited == "[mass]\n# (input file) kg\nsprung = 3.5  # weighed\n[geometry]\nlf = 2.0\n"
    added = add_values(text, {("mass", "unsprung"): (40.0, "new"), ("geometry", "lf"): (2.5, "x")})
    assert added == (
        "[mass]\nsprung = 1.0   # kg\nunsprung = 40.0  # new\n[geometry]\nlf = 2.5  # x\n"
    )
    with pytest.raises(ValueError, match=r"table \[aero\] not found"):
        add_values(text, {("aero", "lift"): (0.1, "x")})


def test_replace_values_edits_lists_in_dotted_tables_and_refuses_a_key_given_twice():
    text = "[suspension.front]\ngaps = [0.1, 0.2]  # m\n"
    edited = replace_values(text, {("suspension", "front", "gaps"): "[0.3, 0.4]"})
    assert edited == "[suspension.front]\ngaps = [0.3, 0.4]  # m\n"
    with pytest.raises(ValueError, match="appears twice"):
        replace_values(text + "gaps = 1\n", {("suspension", "front", "gaps"): "2"})


def test_written_copy_is_checked_and_never_replaces_an_input(tmp_path):
    source = example_vehicle_path()
    text = set_values(source.read_text(encoding="utf-8"), {("mass", "total"): (1613.0, "x")})
    out = write_vehicle_text(text, tmp_path / "car.toml", inputs=(source,), force=False)
    assert load_vehicle(out).mass.total == 1613.0
    with pytest.raises(ValueError, match="exists"):
        write_vehicle_text(text, out, inputs=(source,), force=False)
    with pytest.raises(ValueError, match="is an input file"):
        write_vehicle_text(text, source, inputs=(source,), force=True)
