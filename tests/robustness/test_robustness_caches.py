"""Issue 21, items 3 and 6: caches that cannot be turned against their user, and
interrupted writes that leave nothing behind.

Every test runs the real ``wheelload`` command in a child process on real files.
Each child gets its own TMPDIR, so its own build folder: the build cache of other
processes is never touched. The compiled libraries are built once per session
(:func:`built`) and copied into each test's TMPDIR (gcc is slow under load); the study's
TMPDIR also gets a copy of the libraries this user's build folder already holds (read,
never written), so that the study does not compile the plant and every method again.
"""

import os
import pickle
import shutil
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from wheelload.models import example_vehicle_path
from wheelload.models.runtime.build_folder import build_folder, checked_library
from wheelload.studies.pipeline.example_log import example_log_path

pytestmark = pytest.mark.heavy(38)  # seconds (tests/conftest.py)

COMMAND = [sys.executable, "-m", "wheelload.studies.cli"]


def wheelload(*args, tmpdir: Path, **options) -> subprocess.CompletedProcess:
    env = {**os.environ, "TMPDIR": str(tmpdir)}
    return subprocess.run([*COMMAND, *map(str, args)], capture_output=True, text=True, env=env,
                          **options)  # fmt: skip


#: The command with Ctrl-C's default handling, also when this test runs where SIGINT is
#: ignored (a background job of a shell inherits SIG_IGN, which Python then keeps).
INTERRUPTIBLE = [sys.executable, "-c", "import runpy, signal, sys; "
                 "signal.signal(signal.SIGINT, signal.default_int_handler); "
                 "sys.argv[0] = 'wheelload'; "
                 "runpy.run_module('wheelload.studies.cli', run_name='__main__')"]  # fmt: skip


def start(*args, tmpdir: Path) -> subprocess.Popen:
    """A running ``wheelload`` (interruptible: :data:`INTERRUPTIBLE`)."""
    env = {**os.environ, "TMPDIR": str(tmpdir)}
    return subprocess.Popen([*INTERRUPTIBLE, *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)  # fmt: skip


def stop(process: subprocess.Popen, how: signal.Signals) -> tuple[str, str]:
    """Send ``how`` until ``process`` ends (as a user presses Ctrl-C again: Python drops a
    KeyboardInterrupt raised inside a finaliser); its stdout and stderr."""
    for _ in range(10):
        process.send_signal(how)
        try:
            return process.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            continue
    process.kill()
    return process.communicate()


def build_folder_in(tmpdir: Path) -> Path:
    return tmpdir / f"wheelload-build-{os.getuid()}"


def temporaries(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if ".wltmp-" in p.name)


def one_line(err: str) -> str:
    """The one line said, beside the notes of a build that took over 2 s (a loaded machine
    builds what the copied build folder lacks)."""
    said = [line for line in err.splitlines() if "note: compiling" not in line]
    assert len(said) == 1 and "Traceback" not in err, err
    return said[0] + "\n"


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """A TMPDIR whose build folder holds every library of ``estimate``, and the clean run's
    output file (the reference of the runs below)."""
    tmpdir = tmp_path_factory.mktemp("built")
    out = tmpdir / "clean.csv"
    done = wheelload("estimate", example_log_path(), "--vehicle", example_vehicle_path(),
                     "--out", out, tmpdir=tmpdir)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert sorted(build_folder_in(tmpdir).glob("*.so")), "estimate built no library"
    return tmpdir, out


def copy_build(built, tmp_path: Path) -> Path:
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    shutil.copytree(build_folder_in(built[0]), build_folder_in(tmpdir), symlinks=True)
    return tmpdir


# --- build cache -------------------------------------------------------------------


def test_truncated_libraries_are_rebuilt_with_a_note_and_the_output_equals_a_clean_run(
    built, tmp_path
):
    """Every other library truncated in place (mapped as it is, this was SIGBUS, rc 135), the
    others replaced by a new empty file."""
    tmpdir = copy_build(built, tmp_path)
    libraries = sorted(build_folder_in(tmpdir).glob("*.so"))
    assert len(libraries) >= 2
    sizes = {}
    for k, library in enumerate(libraries):
        assert checked_library(library) is None  # recorded at build time
        if k % 2:
            library.unlink()
            library.write_bytes(b"")
        else:
            os.truncate(library, 4000)
        sizes[library] = library.stat().st_size
        assert checked_library(library) is not None
    out = tmp_path / "loads.csv"
    run = wheelload("estimate", example_log_path(), "--vehicle", example_vehicle_path(),
                    "--out", out, tmpdir=tmpdir)  # fmt: skip
    assert run.returncode == 0, run.stderr
    notes = [line for line in run.stderr.splitlines() if "note: cached library" in line]
    assert len(notes) == len(libraries), run.stderr
    for library, size in sizes.items():
        said = f"{library} is rebuilt: its {size} bytes are not those recorded"
        assert any(said in note for note in notes), (said, notes)
        assert checked_library(library) is None  # built again, with its record
    assert "Traceback" not in run.stderr
    assert out.read_bytes() == built[1].read_bytes()  # the numbers of a clean run, to the bit
    for library in libraries:
        assert library.stat().st_size > 4000 and checked_library(library) is None


@pytest.mark.parametrize("kind", ["mode", "symlink", "owner"])
def test_an_untrusted_build_folder_is_one_line_and_exit_2(tmp_path, kind):
    folder = build_folder_in(tmp_path)
    if kind == "mode":
        folder.mkdir()
        folder.chmod(0o777)
        reason = "has mode 777"
    elif kind == "symlink":
        target = tmp_path / "elsewhere"
        target.mkdir(mode=0o700)
        folder.symlink_to(target)
        reason = "is a symbolic link"
    else:
        if os.geteuid() != 0:
            pytest.skip("giving a folder to another user needs root")
        folder.mkdir(mode=0o700)
        os.chown(folder, 4242, 4242)
        reason = "is owned by user 4242"
    run = wheelload("estimate", "--example", tmpdir=tmp_path)
    assert run.returncode == 2
    err = one_line(run.stderr)
    assert f"{folder}: not a folder private to this user ({reason}" in err
    assert f"rm -r {folder}" in err  # the fix


# --- study cache -------------------------------------------------------------------


STUDY = ("study", "iso-dlc", "--quick", "--workers", "1", "--no-progress")
LONG_STUDY = ("study", "nordschleife", "--workers", "1", "--no-progress")  # minutes


def copy_libraries(source: Path, target: Path) -> None:
    """The compiled outputs of the build folder ``source`` (libraries, their records and
    reports, cached Functions) copied into ``target`` where it has none of that name: no lock,
    no temporary, no object file; ``source`` is only read. A library whose record was copied
    before its own rename into place is built again (checked against the record)."""
    for path in source.iterdir():
        if path.name.startswith(".") or path.suffix in (".lock", ".o", ".d"):
            continue
        if path.is_file() and not (target / path.name).exists():
            shutil.copy2(path, target / path.name)


@pytest.fixture(scope="session")
def study(tmp_path_factory, built):
    """A quick iso-dlc study and its filled cache."""
    tmpdir = tmp_path_factory.mktemp("study_tmp")
    shutil.copytree(build_folder_in(built[0]), build_folder_in(tmpdir), symlinks=True)
    copy_libraries(build_folder(), build_folder_in(tmpdir))
    out = tmp_path_factory.mktemp("study") / "out"
    run = wheelload(*STUDY, "--out", out, tmpdir=tmpdir)
    assert run.returncode == 0, run.stderr
    return tmpdir, out


def study_copy(study, tmp_path: Path) -> Path:
    out = tmp_path / "out"
    shutil.copytree(study[1], out)
    return out


def trial_entries(cache: Path) -> list[Path]:
    """The trials' entries, smallest first (the truth is the largest; recomputing a trial is
    quick)."""
    return sorted(cache.glob("*.npz"), key=lambda p: (p.stat().st_size, p.name))


class _Plant:
    """Unpickling this creates ``path`` (an attacker's payload)."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __reduce__(self):
        return (Path.touch, (self.path,))


def test_damaged_or_planted_entries_are_never_executed_and_each_is_recomputed(study, tmp_path):
    """Four entries spoiled four ways in one study folder; one rerun recomputes exactly those
    four, each with its note, and gives the first run's table to the byte."""
    out = study_copy(study, tmp_path)
    pickled, object_npz, truncated, renamed, donor = trial_entries(out / ".cache")[:5]
    marker = tmp_path / "planted-code-ran"
    pickled.write_bytes(pickle.dumps(_Plant(marker)))
    payload = np.empty(1, dtype=object)  # an NPZ whose member is a pickled object array
    payload[0] = _Plant(marker)
    with object_npz.open("wb") as stream:
        np.savez(stream, manifest=np.frombuffer(b"{}", np.uint8), a0=payload)
    pickle.loads(pickle.dumps(_Plant(tmp_path / "payload-works")))  # the payload is live
    assert (tmp_path / "payload-works").exists()
    os.truncate(truncated, truncated.stat().st_size // 2)
    shutil.copy(donor, renamed)  # a valid entry, but under the wrong name
    run = wheelload(*STUDY, "--out", out, "--force", tmpdir=study[0])
    assert run.returncode == 0, run.stderr
    assert "Traceback" not in run.stderr
    assert not marker.exists()
    notes = [line for line in run.stderr.splitlines() if "note: cache entry" in line]
    assert len(notes) == 4 and all("recomputed" in note for note in notes), run.stderr
    said = {entry: next(note for note in notes if str(entry) in note)
            for entry in (pickled, object_npz, truncated, renamed)}  # fmt: skip
    for entry in (pickled, object_npz, truncated):
        assert "truncated or damaged" in said[entry], said[entry]
    assert "written under another key" in said[renamed]
    assert "4 jobs computed" in run.stdout, run.stdout
    # the recomputed trials are the ones the first run cached: the same table
    table = "iso-dlc_table.csv"
    assert (out / table).read_bytes() == (study[1] / table).read_bytes()


def test_the_cache_folder_is_private(study, tmp_path):
    cache = study[1] / ".cache"
    assert stat.S_IMODE(cache.stat().st_mode) == 0o700
    out = study_copy(study, tmp_path)
    (out / ".cache").chmod(0o755)  # a cache of an earlier version
    run = wheelload(*STUDY, "--out", out, "--force", tmpdir=study[0])
    assert run.returncode == 0, run.stderr
    assert "had mode 755: made private" in run.stderr and "0 jobs computed" in run.stdout
    assert stat.S_IMODE((out / ".cache").stat().st_mode) == 0o700


def test_a_symlinked_cache_folder_is_one_line(study, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / ".cache").symlink_to(study[1] / ".cache")
    run = wheelload(*STUDY, "--out", out, tmpdir=study[0])
    assert run.returncode == 2
    assert "the study cache is a symbolic link" in one_line(run.stderr)


def test_a_second_study_into_the_same_folder_refuses_at_once(built, tmp_path):
    # estimate's libraries only, not the study's: the first run is interrupted while it
    # builds the plant (a Ctrl-C inside the compiled plant's step is not this test's subject)
    tmpdir = copy_build(built, tmp_path)
    out = tmp_path / "out"
    first = start(*LONG_STUDY, "--out", out, tmpdir=tmpdir)
    lock = out / ".wheelload-study.lock"
    while not (lock.exists() and lock.read_text().strip() == str(first.pid)):
        assert first.poll() is None, first.communicate()
        time.sleep(0.02)
    second = wheelload(*STUDY, "--out", out, tmpdir=tmpdir)
    assert first.poll() is None, "the second run waited for the first"
    assert second.returncode == 2, second.stderr
    err = one_line(second.stderr)
    assert f"pid {first.pid}" in err and "give another --out" in err, err
    assert "jobs computed" not in second.stdout
    output, err = stop(first, signal.SIGINT)  # Ctrl-C: one line, exit 130, no temporary left
    assert first.returncode == 130, (output, err)
    assert one_line(err) == "wheelload study: interrupted\n"
    assert temporaries(out) == []


# --- interrupted writes ------------------------------------------------------------


@pytest.fixture(scope="module")
def long_log(tmp_path_factory):
    """The example log repeated 80 times (108 000 samples): written for a few seconds."""
    source = pd.read_csv(example_log_path())
    log = pd.concat([source] * 80, ignore_index=True)
    log["t"] = source["t"].iloc[0] + 0.01 * np.arange(len(log))
    path = tmp_path_factory.mktemp("long") / "long.csv"
    log.to_csv(path, index=False)
    return path


def _interrupt(long_log, built, tmp_path, how):
    """Run ``estimate --out OLD --force``, send ``how`` while its temporary is written."""
    tmpdir = copy_build(built, tmp_path)
    folder = tmp_path / "out"
    folder.mkdir()
    old = folder / "loads.csv"
    old.write_text("the old output\n")
    run = start("estimate", long_log, "--vehicle", example_vehicle_path(), "--out", old,
                "--force", tmpdir=tmpdir)  # fmt: skip
    while not any(p.stat().st_size > 0 for p in temporaries(folder)):
        assert run.poll() is None, run.communicate()
        time.sleep(0.005)
    _, err = stop(run, how)
    assert old.read_text() == "the old output\n"
    return run.returncode, err, folder, tmpdir


@pytest.mark.parametrize(
    "how, code, line",
    [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")],
)
def test_a_signal_mid_write_leaves_no_temporary_and_the_old_output(
    long_log, built, tmp_path, how, code, line
):
    returncode, err, folder, _ = _interrupt(long_log, built, tmp_path, how)
    assert returncode == code, err
    assert one_line(err) == f"wheelload estimate: {line}\n"
    assert sorted(p.name for p in folder.iterdir()) == ["loads.csv"]


def test_a_killed_runs_temporary_is_removed_by_the_next_write(long_log, built, tmp_path):
    returncode, _, folder, tmpdir = _interrupt(long_log, built, tmp_path, signal.SIGKILL)
    assert returncode == -signal.SIGKILL
    (stale,) = temporaries(folder)  # SIGKILL cannot be caught: it stays ...
    alive = folder / f".x.wltmp-{stale.name.split('-')[1]}-{os.getpid()}-live.csv"
    alive.write_text("a temporary of a process that is still running\n")
    run = wheelload("estimate", example_log_path(), "--vehicle", example_vehicle_path(),
                    "--out", folder / "other.csv", tmpdir=tmpdir)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert not stale.exists()  # ... until the folder is written next
    assert alive.exists()  # a live writer's temporary is left alone
    assert (folder / "loads.csv").read_text() == "the old output\n"
