"""The compiled-code cache is private to the user, or refused."""

import os
import re
import stat
from pathlib import Path

import pytest

from wheelload.models.runtime.build_folder import build_folder


def test_build_folder_is_private(tmp_path, monkeypatch):
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)  # re-read TMPDIR
    folder = build_folder()
    assert folder.parent == tmp_path
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    assert folder.stat().st_uid == os.getuid()


def test_a_folder_others_can_write_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)
    shared = tmp_path / f"wheelload-build-{os.getuid()}"
    shared.mkdir(mode=0o777)
    shared.chmod(0o777)
    with pytest.raises(RuntimeError, match="not a folder private to this user"):
        build_folder()


def _private_build_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)


def test_an_object_is_compiled_once_per_text_and_flags(tmp_path, monkeypatch):
    """cached_object: the same C text and flags give the same object file, compiled once
    (the file is not rewritten); a changed header or flag gives a new one; a damaged object
    is compiled again, never linked."""
    from wheelload.models.runtime.build_folder import cached_object

    _private_build_folder(tmp_path, monkeypatch)
    source, header = tmp_path / "tiny.c", tmp_path / "tiny.h"
    header.write_text("#define SCALE 2\n")
    source.write_text('#include "tiny.h"\nint tiny(int x) { return SCALE * x; }\n')
    command = ("gcc", "-O1")
    first = cached_object(source, (header,), command)
    stamp = first.stat().st_mtime_ns
    assert cached_object(source, (header,), command) == first
    assert first.stat().st_mtime_ns == stamp  # not compiled again
    assert cached_object(source, (header,), ("gcc", "-O0")) != first
    header.write_text("#define SCALE 3\n")
    changed = cached_object(source, (header,), command)
    assert changed != first
    changed.write_bytes(changed.read_bytes()[:10])  # truncated
    assert cached_object(source, (header,), command) == changed
    assert len(changed.read_bytes()) > 10  # compiled again


def test_the_compilers_report_is_kept_beside_the_cached_object(tmp_path, monkeypatch):
    """build_report: what gcc printed when it built the object (here a -Wall warning), read
    back later without compiling again; a build without a message leaves an empty report."""
    from wheelload.models.runtime.build_folder import BuildFolderError, build_report, cached_object

    _private_build_folder(tmp_path, monkeypatch)
    source = tmp_path / "noisy.c"
    source.write_text("int noisy(int x) { int unused; return x; }\n")
    built = cached_object(source, (), ("gcc", "-Wall"))
    assert "unused variable 'unused'" in build_report(built)
    stamp = built.stat().st_mtime_ns
    assert cached_object(source, (), ("gcc", "-Wall")) == built
    assert built.stat().st_mtime_ns == stamp  # the report came from the cache
    assert build_report(cached_object(source, (), ("gcc", "-w"))) == ""
    with pytest.raises(BuildFolderError, match="no compiler report"):
        build_report(tmp_path / "absent.o")


def test_processes_that_need_one_object_at_once_compile_it_once(tmp_path):
    """Two processes asking for the same object together (two test workers, two fleet
    workers): one compiles it, the other waits on its lock and takes it. The compiler is
    gcc behind a script that counts its runs and takes 3 s, so that the two overlap."""
    import subprocess
    import sys

    counter = tmp_path / "compilations"
    compiler = tmp_path / "counting-gcc"
    compiler.write_text(f'#!/bin/sh\necho run >> "{counter}"\nsleep 3\nexec gcc "$@"\n')
    compiler.chmod(0o755)
    source, header = tmp_path / "tiny.c", tmp_path / "tiny.h"
    header.write_text("#define SCALE 2\n")
    source.write_text('#include "tiny.h"\nint tiny(int x) { return SCALE * x; }\n')
    program = (
        "from pathlib import Path; from wheelload.models.runtime.build_folder import cached_object;"
        f"print(cached_object(Path('{source}'), (Path('{header}'),), ('{compiler}', '-O1')))"
    )
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    workers = [
        subprocess.Popen(
            [sys.executable, "-c", program], stdout=subprocess.PIPE, text=True, env=env
        )  # fmt: skip
        for _ in range(2)
    ]
    paths = {worker.communicate()[0].strip() for worker in workers}
    assert all(worker.returncode == 0 for worker in workers)
    assert len(paths) == 1 and Path(paths.pop()).is_file()
    assert counter.read_text().count("run") == 1


def test_a_long_compile_is_announced_with_what_why_and_its_time(tmp_path, monkeypatch, caplog):
    """A compile past ANNOUNCE_AFTER (here 0 s, so that a small one is) is announced as a
    note, at the level shown by default: what, why, then done with its time. A library
    loaded from the build folder announces nothing."""
    import logging

    from wheelload.models.runtime import build_folder as folder
    from wheelload.models.runtime.build_folder import keyed_library

    _private_build_folder(tmp_path, monkeypatch)
    # the command line's logging setup (an earlier test in this process) may stop the
    # "wheelload" logger propagating to the root, where caplog listens: listen on it
    monkeypatch.setattr(logging.getLogger("wheelload"), "handlers", [caplog.handler])
    monkeypatch.setattr(logging.getLogger("wheelload"), "propagate", False)
    monkeypatch.setattr(folder, "ANNOUNCE_AFTER", 0.0)
    source = lambda: "int tiny(int x) { return 2 * x; }\n"  # noqa: E731
    with caplog.at_level(logging.WARNING, logger="wheelload"):
        keyed_library("k1", source, "tiny", what="the tiny library", why="first build of it")
    notes = [record.getMessage() for record in caplog.records]
    assert notes[0] == "wheelload: note: compiling the tiny library (first build of it) ..."
    assert re.fullmatch(r"wheelload: note: compiling the tiny library: done in \d+\.\d s", notes[1])
    assert all(record.levelno == logging.WARNING for record in caplog.records)
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="wheelload"):
        keyed_library("k1", source, "tiny", what="the tiny library", why="first build of it")
    assert caplog.records == []
