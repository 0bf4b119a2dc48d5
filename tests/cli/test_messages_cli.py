"""Messages that mean something, on real files: ``-v``/``-vv``/``-q``, the vehicle named,
a user's log without ``--vehicle`` refused, and every option acting or refused in one
line before any long computation."""

import shutil

import pandas as pd
import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.vehicle_choice import vehicle_for_logs


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.fixture
def user_log(tmp_path):
    """The example log copied as a user's: nothing says which car it was recorded on."""
    log = tmp_path / "mine.csv"
    shutil.copy(example_log_path(), log)
    return log


def test_estimate_v_tells_what_was_read_derived_and_timed(tmp_path, capsys):
    frame = pd.read_csv(example_log_path(), comment="#")
    log = tmp_path / "no-rates.csv"
    frame.drop(columns=[c for c in frame.columns if c.startswith("v_")]).to_csv(log, index=False)
    vehicle = str(example_vehicle_path())
    assert main(["estimate", str(log), "--vehicle", vehicle, "-v"]) == 0
    err = capsys.readouterr().err
    assert f"INFO: read {log}: 1353 rows at 100 Hz" in err
    assert "INFO: channel map: none" in err
    assert "INFO: derived: v_* (travel rates) from d_*" in err
    assert f"INFO: vehicle file {vehicle}: 'sports_car', 1613.2 kg" in err
    for name in ("read (time column)", "read (first chunks)", "checks", "filter"):
        assert f"INFO: {name}" in err and " s\n" in err, name
    assert "DEBUG" not in err  # each check's numbers at -vv only


def test_estimate_vv_gives_each_checks_numbers_and_q_only_the_results(tmp_path, capsys):
    out = tmp_path / "e.csv"
    assert main(["estimate", "--example", "--out", str(out), "-vv"]) == 0
    captured = capsys.readouterr()
    assert "DEBUG: wiring check 'd_fl against ay': statistic" in captured.err
    assert "DEBUG: plausibility check 'sample rate': statistic 100, passed" in captured.err
    assert f"INFO: write {out}" in captured.err
    assert "wiring checks:" in captured.out  # a note, shown by default
    assert main(["estimate", "--example", "-q"]) == 0
    quiet = capsys.readouterr()
    assert quiet.err == ""  # not even the bundled car's line
    assert "POOLED" in quiet.out and "wiring checks:" not in quiet.out
    assert main(["estimate", "--example"]) == 0
    err = capsys.readouterr().err
    assert "INFO" not in err and "vehicle: the bundled sports car 'sports_car'" in err


def test_vehicle_v_and_vv(capsys):
    path = str(example_vehicle_path().with_name("suv.toml"))
    assert main(["vehicle", path, "-vv"]) == 0
    err = capsys.readouterr().err
    assert f"INFO: vehicle file {path}: 'suv'" in err and "INFO: model terms on:" in err
    assert "DEBUG: range check 'mass.total' = 2275 in [200, 5e+04]: passed" in err
    assert main(["vehicle", path]) == 0
    assert capsys.readouterr().err == ""


def test_sensor_sets_refuses_a_users_log_without_vehicle(user_log, capsys):
    assert main(["sensor-sets", str(user_log)]) == 2
    err = one_line_error(capsys)
    assert f"{user_log}: give --vehicle FILE" in err and "not meant for your log" in err


def test_simulate_names_the_bundled_car(tmp_path, capsys):
    log = tmp_path / "slope.csv"
    assert main(["simulate", "slope-20", "--out", str(log), "--rate", "50"]) == 0
    captured = capsys.readouterr()
    assert "wheelload simulate: vehicle: the bundled sports car 'sports_car'" in captured.err
    assert captured.out.startswith("slope-20 on vehicle 'sports_car':")
    # the simulated log's metadata names the bundled car: no --vehicle needed on it
    assert vehicle_for_logs(None, [log], "sensor-sets") == example_vehicle_path()
    assert main(["simulate", "slope-20", "--out", str(tmp_path / "q.csv"), "-q"]) == 0
    assert capsys.readouterr().err == ""  # -q: no bundled-car line


@pytest.mark.parametrize(
    "extra, refused",
    [
        (["--logs", "nope.csv"], "--logs is"),
        (["--channels", "map.toml"], "--channels is"),
        (["--sweep", "robust", "--horizon", "5"], "--sweep, --horizon are"),
        (["--scenarios"], "--scenarios is"),
    ],
)
def test_an_experiment_refuses_the_options_it_does_not_use(tmp_path, capsys, extra, refused):
    out = tmp_path / "study"
    assert main(["study", "iso-dlc", "--quick", "--out", str(out), *extra]) == 2
    err = one_line_error(capsys)
    assert f"{refused} not used by study iso-dlc" in err
    assert not out.exists()  # refused before the folder, the lock or any work


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--logs", "nope.csv"], "nope.csv: no such log file (--logs)"),
        (["--cache", "c"], "--cache is not used by study mhe-vs-kf"),
        (["--suspension", "paper"], "--suspension is not used by study mhe-vs-kf"),
        (["--workers", "2"], "--workers is not used by study mhe-vs-kf"),
        (["--sweep", "equivalence", "--faults", "spikes"], "--faults is not used by study "
         "mhe-vs-kf --sweep equivalence"),
        (["--horizons", "5", "10"], "--horizons is not used by study mhe-vs-kf --sweep robust"),
        (["--horizon", "1"], "--horizon must be >= 2"),
    ],
)  # fmt: skip
def test_mhe_vs_kf_checks_its_options_and_logs_first(tmp_path, capsys, extra, message):
    out = tmp_path / "mvk"
    assert main(["study", "mhe-vs-kf", "--out", str(out), "--scenarios", *extra]) == 2
    assert message in one_line_error(capsys)
    assert not list(tmp_path.iterdir())


def test_mhe_vs_kf_refuses_a_users_log_without_vehicle(user_log, tmp_path, capsys):
    out = tmp_path / "mvk"
    assert main(["study", "mhe-vs-kf", "--logs", str(user_log), "--out", str(out)]) == 2
    assert f"{user_log}: give --vehicle FILE" in one_line_error(capsys)


def test_tune_checks_its_evaluate_logs_before_the_fit(user_log, tmp_path, capsys):
    out = tmp_path / "tuned.toml"
    vehicle = str(example_vehicle_path())
    argv = ["tune", str(user_log), "--vehicle", vehicle, "--out", str(out)]
    assert main([*argv, "--evaluate", str(tmp_path / "nope.csv")]) == 2
    assert "nope.csv: no such log file (--evaluate)" in one_line_error(capsys)
    frame = pd.read_csv(example_log_path(), comment="#")
    bare = tmp_path / "bare.csv"
    frame.drop(columns=[c for c in frame.columns if c.startswith("fz_")]).to_csv(bare, index=False)
    assert main([*argv, "--evaluate", str(bare)]) == 2
    assert f"{bare}: no reference loads" in one_line_error(capsys)
    assert not out.exists()  # nothing written before the arguments were checked


def test_compare_creates_its_figures_folder_and_names_the_vehicle(tmp_path, capsys):
    folder = tmp_path / "figures" / "new"
    argv = ["compare", str(example_log_path()), "--vehicle", str(example_vehicle_path())]
    assert main([*argv, "--methods", "C", "--repeat", "1", "--figures", str(folder)]) == 0
    assert "example_drive.csv on vehicle 'sports_car'" in capsys.readouterr().out
    assert sorted(p.name for p in folder.iterdir()) == [
        f"example_drive_compare_{w}.png" for w in ("fl", "fr", "rl", "rr")
    ]
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert main([*argv, "--methods", "C", "--figures", str(afile)]) == 2
    assert "exists and is not a folder" in one_line_error(capsys)
