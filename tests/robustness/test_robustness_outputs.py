"""Item 1: no command overwrites an input or an existing file without --force (real files)."""

import os

import pandas as pd
import pytest
from c_parity import kf_program, run_program

from wheelload.estimators.logs.output_files import OutputError, atomic_write
from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("force", [[], ["--force"]])
def test_estimate_never_writes_over_its_log_or_vehicle(user_files, capsys, force):
    log, vehicle = user_files
    log_bytes, vehicle_bytes = log.read_bytes(), vehicle.read_bytes()
    for target in (log, vehicle):
        assert main(["estimate", str(log), "--vehicle", str(vehicle), "--out", str(target),
                     *force]) == 2  # fmt: skip
        assert "is the input file" in one_line_error(capsys)
    assert log.read_bytes() == log_bytes and vehicle.read_bytes() == vehicle_bytes


@pytest.mark.parametrize("link", ["hard", "symbolic", "dotted"])
def test_estimate_sees_through_links_to_its_log(user_files, capsys, link):
    log, vehicle = user_files
    alias = log.parent / "alias.csv"
    if link == "hard":
        os.link(log, alias)
    elif link == "symbolic":
        alias.symlink_to(log)
    else:
        alias = log.parent / "." / ".." / log.parent.name / log.name
    before = log.read_bytes()
    code = main(["estimate", str(log), "--vehicle", str(vehicle), "--out", str(alias), "--force"])
    assert code == 2 and "is the input file" in one_line_error(capsys)
    assert log.read_bytes() == before


def test_estimate_replaces_an_existing_output_only_with_force(user_files, capsys, tmp_path):
    log, vehicle = user_files
    out = tmp_path / "loads.csv"
    out.write_text("my own notes\n")
    assert main(["estimate", str(log), "--vehicle", str(vehicle), "--out", str(out)]) == 2
    assert "exists" in one_line_error(capsys) and out.read_text() == "my own notes\n"
    assert main(["estimate", str(log), "--vehicle", str(vehicle), "--out", str(out),
                 "--force"]) == 0  # fmt: skip
    assert len(pd.read_csv(out)) == 1353
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temp left


def test_estimate_out_suffix_decides_the_format(user_files, capsys, tmp_path):
    log, vehicle = user_files
    parquet = tmp_path / "loads.parquet"
    assert main(["estimate", str(log), "--vehicle", str(vehicle), "--out", str(parquet)]) == 0
    assert parquet.read_bytes()[:4] == b"PAR1"
    frame = pd.read_parquet(parquet)
    assert len(frame) == 1353 and "fz_fl" in frame.columns
    capsys.readouterr()
    assert main(["estimate", str(log), "--vehicle", str(vehicle), "--out",
                 str(tmp_path / "loads.txt")]) == 2  # fmt: skip
    assert "unknown table format '.txt'" in one_line_error(capsys)
    assert not (tmp_path / "loads.txt").exists()


def test_simulate_refuses_an_existing_log_or_sidecar_before_simulating(tmp_path, capsys):
    log = tmp_path / "run.csv"
    log.write_text("precious\n")
    assert main(["simulate", "iso-dlc", "--out", str(log)]) == 2
    assert "run.csv: exists" in one_line_error(capsys) and log.read_text() == "precious\n"
    sidecar = tmp_path / "other.csv.meta.json"
    sidecar.write_text("{}\n")
    assert main(["simulate", "iso-dlc", "--out", str(tmp_path / "other.csv")]) == 2
    assert "other.csv.meta.json: exists" in one_line_error(capsys)
    assert not (tmp_path / "other.csv").exists()
    vehicle = tmp_path / "car.csv"
    vehicle.write_bytes(example_vehicle_path().read_bytes())
    code = main(["simulate", "iso-dlc", "--vehicle", str(vehicle), "--out", str(vehicle),
                 "--force"])  # fmt: skip
    assert code == 2 and "is the input file" in one_line_error(capsys)


def test_study_refuses_an_output_prefix_that_names_a_log(user_files, capsys):
    log, _ = user_files
    before = log.read_bytes()
    code = main(["study", "mhe-vs-kf", "--logs", str(log), "--out", str(log.with_suffix(""))])
    assert code == 2 and "is the input file" in one_line_error(capsys)
    assert log.read_bytes() == before


def test_codegen_writes_only_into_a_new_or_empty_folder(tmp_path, capsys):
    folder = tmp_path / "c"
    folder.mkdir()
    (folder / "Makefile").write_text("all:\n\techo mine\n")
    assert main(["codegen", "--out", str(folder)]) == 2
    assert "is not empty (has 'Makefile')" in one_line_error(capsys)
    assert (folder / "Makefile").read_text() == "all:\n\techo mine\n"
    assert main(["codegen", "--out", str(folder), "--force"]) == 0
    assert "wheelload" in (folder / "Makefile").read_text()
    vehicle = folder / "car.toml"
    vehicle.write_bytes(example_vehicle_path().read_bytes())
    capsys.readouterr()
    assert main(["codegen", "--out", str(folder), "--vehicle", str(vehicle), "--force"]) == 2
    assert "holds the input file" in one_line_error(capsys)


def test_atomic_write_leaves_the_old_file_on_an_error(tmp_path):
    target = tmp_path / "loads.csv"
    target.write_text("old\n")
    with pytest.raises(RuntimeError), atomic_write(target, replace=True) as temporary:
        temporary.write_text("half")
        raise RuntimeError("interrupted")
    assert target.read_text() == "old\n" and sorted(tmp_path.iterdir()) == [target]
    with pytest.raises(OutputError, match="appeared while writing"):
        with atomic_write(target) as temporary:
            temporary.write_text("new\n")
    assert target.read_text() == "old\n"


@pytest.fixture(scope="module")
def example_program(tmp_path_factory):
    folder = tmp_path_factory.mktemp("example_program")
    return kf_program(example_vehicle_path(), folder)


def test_example_program_refuses_to_write_over_its_log(example_program, user_files):
    log, _ = user_files
    before = log.read_bytes()
    hard, symbolic = log.parent / "hard.csv", log.parent / "symbolic.csv"
    os.link(log, hard)
    symbolic.symlink_to(log)
    for target in (log, hard, symbolic, log.parent / "." / log.name):
        result = run_program(example_program, log, target, check=False)
        assert result.returncode == 2 and "is the input log" in result.stderr
        assert log.read_bytes() == before


def test_example_program_replaces_its_output_only_when_complete(example_program, user_files):
    log, _ = user_files
    out = log.parent / "estimates.csv"
    out.write_text("previous result\n")
    bad = log.parent / "bad.csv"
    lines = log.read_text().splitlines()
    lines[40] = lines[40].replace(",", ",oops", 1)
    bad.write_text("\n".join(lines) + "\n")
    result = run_program(example_program, bad, out, check=False)
    assert result.returncode == 2 and "not a decimal number" in result.stderr
    assert out.read_text() == "previous result\n"
    assert sorted(p.name for p in log.parent.iterdir()) == sorted(
        ["drive.csv", "car.toml", "bad.csv", "estimates.csv"]
    )
    result = run_program(example_program, log, out, check=False)
    assert result.returncode == 0, result.stderr
    assert len(pd.read_csv(out)) == 1353
    assert oct(out.stat().st_mode & 0o777) == oct(0o666 & ~current_umask())


def current_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
