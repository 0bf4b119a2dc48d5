"""``wheelload codegen``: the command writes a library that its own Makefile builds and runs."""

import subprocess
import zipfile

import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main

pytestmark = pytest.mark.heavy(19)  # seconds (tests/conftest.py)


def test_codegen_command_writes_a_library_its_makefile_builds(tmp_path, capsys):
    out = tmp_path / "c"
    argv = ["codegen", "--vehicle", str(example_vehicle_path()), "--out", str(out),
            "--precision", "float", "--params", "baked", "--prefix", "car7"]  # fmt: skip
    assert main(argv) == 0
    assert "arithmetic operations per step" in capsys.readouterr().out
    assert {"car7.h", "car7.c", "car7_example.c", "car7_selftest.c", "Makefile"} <= {
        path.name for path in out.iterdir()
    }
    assert "typedef float car7_real;" in (out / "car7.h").read_text()
    subprocess.run(["make", "-s", "-C", str(out)], check=True, capture_output=True)
    log = tmp_path / "no_rates.csv"
    log.write_text(
        "t,vx,ax,ay,az,d_fl,d_fr,d_rl,d_rr\n0,0,0,0,9.81,0,0,0,0\n0.01,0,0,0,9.81,0,0,0,0\n"
    )
    result = subprocess.run([str(out / "car7_example"), str(log)], capture_output=True, text=True)
    assert result.returncode == 2
    assert "missing column 'v_fl'" in result.stderr


def test_codegen_command_names_a_bad_prefix(tmp_path, capsys):
    argv = ["codegen", "--vehicle", str(example_vehicle_path()), "--out", str(tmp_path),
            "--prefix", "9lives"]  # fmt: skip
    assert main(argv) == 2
    assert "prefix '9lives'" in capsys.readouterr().err


def test_codegen_command_writes_the_embedded_mhe(tmp_path, capsys):
    out = tmp_path / "mhe"
    argv = ["codegen", "--estimator", "mhe", "--out", str(out), "--horizon", "5",
            "--constraint", "hard", "--bounded", "--interval", "0.005",
            "--precision", "float"]  # fmt: skip
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "MHE N=5 (hard, bounded)" in printed and "dt = 0.005 s" in printed
    assert "projection KF linked in" in printed  # the hard window's fallback, as in Python
    files = {"wheelload_mhe.c", "wheelload_mhe_terms.c", "wheelload_mhe_kf.c", "osqp"}
    assert files <= {p.name for p in out.iterdir()}
    assert sorted(p.name for p in out.iterdir() if p.name not in _help_files(capsys)) == []
    assert "#define DT 0.005" in (out / "wheelload_mhe.c").read_text()
    assert "#define OSQP_USE_FLOAT" in (out / "osqp" / "osqp_configure.h").read_text()
    # Its own Makefile builds the static library (relative paths: the folder may move).
    moved = tmp_path / "moved"
    out.rename(moved)
    subprocess.run(["make", "-s", "-C", str(moved)], check=True, capture_output=True)
    symbols = subprocess.run(["nm", str(moved / "libwheelload_mhe.a")], check=True,
                             capture_output=True, text=True).stdout  # fmt: skip
    assert " T wheelload_mhe_step" in symbols and " T wheelload_mhe_kf_step" in symbols


def _help_files(capsys) -> set[str]:
    """The file names ``wheelload codegen --help`` gives (``NAME.c/.h``: both, ``osqp/``: the
    folder)."""
    with pytest.raises(SystemExit):
        main(["codegen", "--help"])
    words = {w.rstrip(".,;:)/") for w in capsys.readouterr().out.replace("(", " ").split()}
    pairs = {f"{w[:-5]}.{end}" for w in words if w.endswith(".c/.h") for end in "ch"}
    return words | pairs


def test_codegen_command_rejects_the_other_estimators_options(tmp_path, capsys):
    assert main(["codegen", "--out", str(tmp_path), "--horizon", "5", "--bounded"]) == 2
    assert "--horizon, --bounded: not an option of --estimator kf" in capsys.readouterr().err
    argv = ["codegen", "--estimator", "mhe", "--out", str(tmp_path), "--prefix", "car7"]
    assert main(argv) == 2
    assert "--prefix: not an option of --estimator mhe" in capsys.readouterr().err


def test_codegen_mhe_refuses_a_folder_with_files_and_replaces_them_with_force(tmp_path, capsys):
    out = tmp_path / "mhe"
    out.mkdir()
    mine = out / "wheelload_mhe.c"
    mine.write_text("/* the user's own file */\n")
    argv = ["codegen", "--estimator", "mhe", "--out", str(out), "--horizon", "3"]
    assert main(argv) == 2
    assert "is not empty" in capsys.readouterr().err
    assert mine.read_text() == "/* the user's own file */\n"
    assert main([*argv, "--force"]) == 0
    assert "#define N WHEELLOAD_MHE_N" in mine.read_text()
    assert "#define WHEELLOAD_MHE_N 3" in (out / "wheelload_mhe_state.h").read_text()
    # every file renamed into place: no temporary file or staging folder is left behind
    assert not [p for p in out.rglob("*") if p.name.startswith(".")]


def test_codegen_mhe_writes_the_robust_bias_lagged_window_with_the_kf_linked_in(tmp_path, capsys):
    out = tmp_path / "mhe"
    argv = ["codegen", "--estimator", "mhe", "--out", str(out), "--horizon", "4", "--bounded",
            "--suspension-loss", "huber", "--huber-threshold", "1.5", "--constraint-loss", "l1",
            "--bias-states", "travel+acceleration", "--lag", "2"]  # fmt: skip
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "susp huber 1.5σ, eq l1, travel+ax/ay bias, lag 2" in printed
    assert "two-stage KF linked in" in printed
    source = (out / "wheelload_mhe.c").read_text()
    assert "#define LAG 2" in source and "#define NB WHEELLOAD_MHE_NB" in source
    assert "#define WHEELLOAD_MHE_NB 5" in (out / "wheelload_mhe_state.h").read_text()
    assert "#define KALMAN_ARRIVAL 1" in source and "#define MU_S 1.5" in source
    assert (out / "wheelload_mhe_kf.c").exists() and (out / "wheelload_mhe.h").exists()
    assert main(["codegen", "--out", str(tmp_path / "kf"), "--lag", "2"]) == 2
    assert "--lag: not an option of --estimator kf" in capsys.readouterr().err


def test_the_generated_makefile_takes_gcc_unless_cc_is_given(tmp_path, capsys):
    """make's built-in ``CC = cc`` does not count: gcc by default, the user's CC otherwise
    (``make -n`` prints the commands without running them)."""
    import os

    out = tmp_path / "c"
    assert main(["codegen", "--out", str(out)]) == 0
    environment = {k: v for k, v in os.environ.items() if k != "CC"}

    def commands(*args, **extra):
        return subprocess.run(["make", "-n", "-C", str(out), *args], check=True,
                              capture_output=True, text=True, env={**environment, **extra}
                              ).stdout  # fmt: skip

    built = [line for line in commands().splitlines() if " -o " in line]
    # the library's object once, then the example and the self-test linked with it
    assert len(built) == 3 and all(line.startswith("gcc -std=c99") for line in built)
    assert sum(" -c " in line for line in built) == 1
    assert "my-cc -std=c99" in commands(CC="my-cc")
    assert "other-cc -std=c99" in commands("CC=other-cc")


def test_codegen_fmu_writes_one_source_fmu_and_refuses_baked_parameters(tmp_path, capsys):
    """``--fmu`` writes OUT/PREFIX.fmu alone (the FMU's own tests: tests/estimators/codegen/
    test_fmu.py); baked parameters, which an FMU could not tune, are refused in one line."""
    out = tmp_path / "fmu"
    assert main(["codegen", "--fmu", "--out", str(out), "--prefix", "car7"]) == 0
    assert str(out / "car7.fmu") in capsys.readouterr().out
    assert [path.name for path in out.iterdir()] == ["car7.fmu"]
    with zipfile.ZipFile(out / "car7.fmu") as archive:
        names = set(archive.namelist())
    assert {"modelDescription.xml", "sources/buildDescription.xml", "sources/car7_fmu.c",
            "sources/car7_tyre.c"} <= names  # fmt: skip
    argv = ["codegen", "--fmu", "--params", "baked", "--out", str(tmp_path / "baked")]
    assert main(argv) == 2
    assert "--fmu: the FMU's tunable parameters" in capsys.readouterr().err
    assert not (tmp_path / "baked").exists()
