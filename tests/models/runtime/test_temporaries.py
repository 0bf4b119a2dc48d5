"""Temporaries named by their owner: a gone writer's are removed, a live one's are kept."""

import os
import subprocess
import sys

from wheelload.models.runtime import temporaries
from wheelload.models.runtime.temporaries import remove_stale, replacing, temporary_file


def _dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid  # reaped: no process has this id (until it is reused)


def test_only_the_temporaries_of_gone_writers_on_this_host_are_removed(tmp_path):
    host = temporaries._host()
    mine = temporary_file(tmp_path, "loads", ".csv")
    assert mine.name.startswith(f".loads.wltmp-{host}-{os.getpid()}-") and mine.suffix == ".csv"
    dead = tmp_path / f".loads.wltmp-{host}-{_dead_pid()}-abc.csv"
    other_host = tmp_path / f".loads.wltmp-00000000-{_dead_pid()}-abc.csv"
    old = tmp_path / f".loads.wltmp-00000000-{os.getpid()}-old.csv"
    plain = tmp_path / ".loads-abc.csv"  # looks temporary, but not one of ours: kept
    for path in (dead, other_host, old, plain):
        path.write_text("x")
    os.utime(old, (0, 0))  # older than STALE_SECONDS (its process id may have been reused)
    assert sorted(remove_stale(tmp_path)) == sorted([dead, old])
    assert mine.exists() and other_host.exists() and plain.exists()


def test_replacing_renames_on_success_and_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "table.csv"
    target.write_text("old")
    try:
        with replacing(target) as temporary:
            temporary.write_text("half")
            raise RuntimeError("writer failed")
    except RuntimeError:
        pass
    assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == [
        "table.csv"
    ]
    with replacing(target, mode=0o640) as temporary:
        temporary.write_text("new")
    assert target.read_text() == "new" and (target.stat().st_mode & 0o777) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]
