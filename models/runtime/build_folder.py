"""Where generated code is compiled: a private folder of the current user.

Compiled libraries are cached by the hash of their source, so the folder
must be writable by this user alone: ``<system temp>/wheelload-build-<uid>``,
mode 0700, owned by the user, not a symbolic link. Anything else is refused
with a :class:`BuildFolderError` (one line on the command line) rather than
trusted.

A cached library is loaded only after a check: its size and SHA-256 are
recorded at build time in a sidecar file (``<library>.sha256``, renamed into
place before the library itself), and a library that does not match (truncated,
damaged, or without its record) is built again with a one-line note, never
mapped (a truncated library mapped into memory kills the process with SIGBUS).

What the compiler printed while building an output (its warnings, and the reports asked
for by flags such as ``-fopt-info``) is kept beside it (``<output>.report``,
:func:`build_report`), so a cached build says what gcc said of it without compiling again.

A compile still running after :data:`ANNOUNCE_AFTER` seconds is announced on the
``wheelload`` logger at the level of notes (shown at the default verbosity): what is being
built and why, then ``done`` with its time, so that a long first build is never silent.
"""

from __future__ import annotations

import contextlib
import ctypes
import fcntl
import hashlib
import logging
import os
import stat
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

from wheelload.models.runtime.temporaries import remove_stale, temporary_file

_log = logging.getLogger(__name__)


class BuildFolderError(RuntimeError):
    """The build folder cannot be trusted or no library can be built: names it and the fix."""


def build_folder() -> Path:
    """The private build folder, created on first use; a :class:`BuildFolderError` otherwise."""
    folder = Path(tempfile.gettempdir()) / f"wheelload-build-{os.getuid()}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
    except OSError as error:
        raise BuildFolderError(
            f"{folder}: cannot make the build folder ({error.strerror}): "
            "set TMPDIR to a folder of your own"
        ) from None
    info = folder.lstat()
    mode = stat.S_IMODE(info.st_mode)
    if stat.S_ISLNK(info.st_mode):
        reason = "is a symbolic link"
    elif not stat.S_ISDIR(info.st_mode):
        reason = "is not a folder"
    elif info.st_uid != os.getuid():
        reason = f"is owned by user {info.st_uid}"
    elif mode & 0o077:
        reason = f"has mode {mode:o}: others may enter it"
    else:
        return folder
    raise BuildFolderError(
        f"{folder}: not a folder private to this user ({reason}): remove it "
        f"(rm -r {folder}) so that it can be made again with mode 700"
    )


def jit_options() -> dict:
    """CasADi JIT with the system C compiler, building in :func:`build_folder`."""
    return {
        "jit": True,
        "compiler": "shell",
        "jit_options": {"flags": ["-O2"], "directory": f"{build_folder()}{os.sep}"},
    }


#: Flags of the plant's compiled chunk (as the CasADi JIT it replaces: ``-O2``).
CHUNK_FLAGS = ("-O2", "-fPIC", "-shared")


def _record(data: bytes) -> str:
    """The sidecar's text: size and SHA-256 of a library's bytes."""
    return f"{len(data)} {hashlib.sha256(data).hexdigest()}\n"


def _sidecar(library: Path) -> Path:
    return library.with_name(library.name + ".sha256")


def _report(output: Path) -> Path:
    return output.with_name(output.name + ".report")


def build_report(output: Path) -> str:
    """What the compiler printed on standard error while building the cached ``output``
    (warnings, ``-fopt-info`` reports; empty when it said nothing)."""
    try:
        return _report(output).read_text()
    except OSError as error:
        raise BuildFolderError(
            f"{output}: no compiler report ({error.strerror}): remove it so that it is built again"
        ) from None


def checked_library(library: Path) -> str | None:
    """Why ``library`` may not be loaded (its record is missing or it does not match), or
    None when its size and hash are those recorded at build time (module docstring)."""
    try:
        recorded = _sidecar(library).read_text(encoding="ascii")
    except (OSError, UnicodeDecodeError):
        return "it has no build record"
    try:
        data = library.read_bytes()
    except OSError as error:
        return f"it cannot be read ({error.strerror})"
    if _record(data) != recorded:
        return f"its {len(data)} bytes are not those recorded at build time"
    return None


def _put(folder: Path, target: Path, data: bytes) -> None:
    """Write ``data`` to ``target`` through a temporary renamed into place."""
    temporary = temporary_file(folder, target.stem, target.suffix)
    try:
        temporary.write_bytes(data)
        os.replace(temporary, target)
    finally:
        temporary.unlink(missing_ok=True)


def _compile(
    sources: dict[str, str], target: Path, command: tuple[str, ...], purpose: str
) -> tuple[bytes, str]:
    """The bytes ``command`` makes of ``sources`` (file name: text; the first is compiled, the
    others are the headers it includes), in a temporary folder of the build folder (fixed file
    names inside it, so that the same sources give the same bytes), and what it printed on
    standard error (in the C locale)."""
    import shutil  # only to build: a warm run loads what is built
    import subprocess

    folder = target.parent
    work = temporary_file(folder, target.stem, ".d")
    work.unlink()
    work.mkdir(mode=0o700)
    try:
        for file_name, text in sources.items():
            (work / file_name).parent.mkdir(parents=True, exist_ok=True)
            (work / file_name).write_text(text)
        output = work / target.name
        link = () if "-c" in command else ("-lm",)
        try:
            done = subprocess.run(
                [*command, "-o", output.name, next(iter(sources)), *link],
                check=True,
                capture_output=True,
                text=True,
                cwd=work,
                env={**os.environ, "LC_ALL": "C"},  # the report in one language
            )
        except FileNotFoundError:
            raise BuildFolderError(
                f"no C compiler '{command[0]}' found: it is needed to {purpose}; install gcc"
            ) from None
        except subprocess.CalledProcessError as error:
            raise RuntimeError(f"compiling {target.stem} failed:\n{error.stderr}") from None
        return output.read_bytes(), done.stderr
    finally:
        shutil.rmtree(work, ignore_errors=True)


#: Seconds a compile runs before it is announced (module docstring).
ANNOUNCE_AFTER = 2.0


@contextlib.contextmanager
def _announced(what: str, why: str):
    """Log ``compiling <what> (<why>) ...`` once the block has run :data:`ANNOUNCE_AFTER`
    seconds, and ``... done in <t> s`` when it ends; nothing for a shorter block."""
    start = time.perf_counter()
    announced = threading.Event()

    def announce() -> None:
        announced.set()
        _log.warning("wheelload: note: compiling %s (%s) ...", what, why)

    timer = threading.Timer(ANNOUNCE_AFTER, announce)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
        if announced.is_set():
            seconds = time.perf_counter() - start
            _log.warning("wheelload: note: compiling %s: done in %.1f s", what, seconds)


def _cached_build(key: str, sources: Callable[[], dict[str, str]], name: str, suffix: str,
                  command: tuple[str, ...], load, purpose: str,
                  what: str | None = None, why: str = "first build of this source"):  # fmt: skip
    """``load`` of what ``command`` makes of ``sources()`` (:func:`_compile`), made once.

    The output is named by the hash of the command and ``key`` (the sources' text, or what
    determines them: :func:`keyed_library`), built under :func:`build_folder`, the
    compiler's report (:func:`build_report`), the record (size and SHA-256) and then the
    output renamed into place. A cached output is used only when it matches its record
    (:func:`checked_library`); one that does not, or does not load, is built again with a
    one-line note. A long build is announced (:func:`_announced`) as ``what`` (default: the
    output's name) and ``why``.
    """
    digest = hashlib.sha256((" ".join(command) + key).encode()).hexdigest()[:16]
    folder = build_folder()
    target = folder / f"{name}_{digest}{suffix}"
    with _held(target):
        if target.exists():
            problem = checked_library(target)
            if problem is None:
                try:
                    return load(target)
                except (OSError, RuntimeError) as error:
                    first = (str(error) or type(error).__name__).splitlines()[0]
                    problem = f"it does not load ({first})"
            _log.warning("wheelload: note: cached library %s is rebuilt: %s", target, problem)
            why = f"the cached build is damaged: {problem}"
        remove_stale(folder)
        with _announced(what or target.name, why):
            data, report = _compile(sources(), target, command, purpose)
        _put(folder, _report(target), report.encode())
        # The record first: an output in place always has its record, and a crash between
        # the two renames leaves a record without its output (built again, never used).
        _put(folder, _sidecar(target), _record(data).encode("ascii"))
        _put(folder, target, data)
    return load(target)


@contextlib.contextmanager
def _held(target: Path):
    """An exclusive lock on ``<target>.lock`` while ``target`` is checked or built: processes
    that need the same output at once (test workers, a fleet's) build it once, the others
    wait for it and then find it in place. The lock ends with the process that holds it."""
    with open(target.with_name(target.name + ".lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield


#: gcc and its flags for the small shared libraries of the compiled loops and kernels
#: (-std=c99: no FMA contraction, so C gives Python's numbers).
COMPILER = ("gcc", "-O2", "-std=c99", "-fPIC", "-shared")


def cached_library(source: str, name: str, command: tuple[str, ...], load, purpose: str,
                   what: str | None = None, why: str = "first build of this source"):  # fmt: skip
    """``source`` compiled once by ``command`` (gcc and its flags) into a shared library
    loaded with ``load`` (:func:`_cached_build`). ``purpose`` completes "gcc is needed to ...";
    ``what`` and ``why`` name a long build (:func:`_announced`)."""
    sources = {f"{name}.c": source}
    return _cached_build(_sources_key(sources), lambda: sources, name, ".so", command, load,
                         purpose, what, why)  # fmt: skip


def _sources_key(sources: dict[str, str]) -> str:
    return "".join(f"\n{file}\n{body}" for file, body in sources.items())


def cached_object(source: Path, headers: tuple[Path, ...], command: tuple[str, ...],
                  root: Path | None = None) -> Path:  # fmt: skip
    """The object file ``command`` (compiler and flags, ``-c`` added) makes of the C file
    ``source`` including ``headers``, compiled once per text and command
    (:func:`_cached_build`): a large generated library is compiled once however many
    programs link it. The files keep their paths relative to ``root`` (default: the
    source's folder), so ``-I`` flags in ``command`` are relative to it."""
    root = source.parent if root is None else root
    files = {str(path.relative_to(root)): path.read_text() for path in (source, *headers)}
    name = source.stem
    return _cached_build(_sources_key(files), lambda: files, name, ".o", (*command, "-c"), Path,
                         "build the program")  # fmt: skip


def cached_function(function):
    """``function`` as generated C, compiled once per source and loaded (``casadi.external``).

    The library is named by the hash of its C source and flags (which hold
    every parameter baked into the expressions), so a second process with the
    same model loads it instead of compiling again (the CasADi JIT compiles on
    every call); see :func:`cached_library`.
    """
    import casadi as ca

    name = function.name()
    generator = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    generator.add(function)
    return cached_library(
        generator.dump(),
        name,
        ("gcc", *CHUNK_FLAGS),
        lambda library: ca.external(name, str(library)),
        "compile the plant",
    )


def shared_library(
    source: str,
    name: str,
    compiler: tuple[str, ...] = COMPILER,
    purpose: str = "run the filter over a log in compiled code",
    *,
    what: str | None = None,
    why: str = "first build of this source",
) -> ctypes.CDLL:
    """``source`` compiled once (:func:`cached_library`) and loaded with ctypes."""
    load = lambda library: ctypes.CDLL(str(library))  # noqa: E731
    return cached_library(source, name, compiler, load, purpose, what, why)


def keyed_library(
    key: str,
    source: Callable[[], str],
    name: str,
    purpose: str = "run the filter over a log in compiled code",
    *,
    what: str | None = None,
    why: str = "first build of this code",
) -> ctypes.CDLL:
    """As :func:`shared_library`, named by ``key`` instead of the source's text: ``source()``
    is generated only when the library is built. ``key`` must determine the source (a hash
    of the code that generates it, :func:`~wheelload.models.runtime.function_cache.code_digest`,
    and the arguments it is generated from), so that a changed source never meets a
    library built from another. ``what`` and ``why`` name a long build (:func:`_announced`)."""
    return _cached_build(
        f"\nkey {key}",
        lambda: {f"{name}.c": source()},
        name,
        ".so",
        COMPILER,
        lambda library: ctypes.CDLL(str(library)),
        purpose,
        what,
        why,
    )
