"""Output files that never destroy a user's data.

Every command that writes checks its outputs first with
:func:`check_outputs` (an output equal to an input is always refused; an
existing output only with ``force``), then writes each one through
:func:`atomic_write`: a temporary file in the target folder, renamed into
place once complete, so an interrupted run leaves the old file or nothing
(and no temporary: :func:`atomic_write`).

Example
-------
>>> check_outputs([Path("loads.csv")], [Path("drive.csv")], force=False)
>>> with atomic_write(Path("loads.csv")) as temporary:
...     frame.to_csv(temporary, index=False)
"""

from __future__ import annotations

import contextlib
import enum
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

from wheelload.models.runtime import interrupts
from wheelload.models.runtime.temporaries import temporary_file


class OutputError(ValueError):
    """An output that must not be written: names the file and the fix."""


class TableFormat(enum.Enum):
    """File format of a table, chosen by the file's suffix."""

    CSV = ".csv"
    PARQUET = ".parquet"


#: Figure formats matplotlib writes, by suffix.
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def table_format(path: Path) -> TableFormat:
    """The format ``path``'s suffix names, or an :class:`OutputError`."""
    for fmt in TableFormat:
        if path.suffix.lower() == fmt.value:
            return fmt
    raise OutputError(
        f"{path}: unknown table format '{path.suffix}': name the file .csv or .parquet"
    )


def check_figure_suffix(path: Path) -> None:
    """A figure's suffix must be one matplotlib writes (:data:`FIGURE_SUFFIXES`)."""
    if path.suffix.lower() not in FIGURE_SUFFIXES:
        raise OutputError(
            f"{path}: unknown figure format '{path.suffix}': name the file "
            + ", ".join(FIGURE_SUFFIXES)
        )


def _same_file(a: Path, b: Path) -> bool:
    """True if ``a`` and ``b`` name one file (same resolved path, or same device and inode)."""
    if a.resolve() == b.resolve():
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def check_folder(folder: Path, path: Path) -> None:
    """``path``'s folder must exist and be writable, or an :class:`OutputError`."""
    if not folder.is_dir():
        raise OutputError(f"{path}: folder '{folder}' does not exist: create it first")
    try:  # a real probe: permissions, read-only mounts, and root alike
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as error:
        raise OutputError(
            f"{path}: cannot write in folder '{folder}' ({error.strerror}): choose another folder"
        ) from None


def check_outputs(outputs: Sequence[Path], inputs: Sequence[Path], *, force: bool) -> None:
    """Refuse outputs that would destroy data, before any work is done.

    An output that is the same file as an input is refused even with
    ``force``; an existing output is refused unless ``force``; two outputs
    may not name one file; the output's folder must exist and be writable.
    """
    outputs, inputs = [Path(p) for p in outputs], [Path(p) for p in inputs]
    for k, out in enumerate(outputs):
        for source in inputs:
            if _same_file(out, source):
                raise OutputError(
                    f"{out}: is the input file '{source}': choose another output name "
                    "(--force never overwrites an input)"
                )
        for other in outputs[:k]:
            if _same_file(out, other):
                raise OutputError(f"{out}: named twice as an output: choose two names")
        if out.is_dir():
            raise OutputError(f"{out}: is a folder: give a file name")
        if out.exists() and not force:
            raise OutputError(f"{out}: exists: choose another name or give --force to replace it")
        check_folder(out.parent, out)


def check_output_folder(folder: Path, inputs: Sequence[Path], *, force: bool) -> None:
    """A folder for generated files: new or empty, or any folder with ``force``.

    The folder may not contain an input (e.g. the vehicle file), even with ``force``.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{folder}: is a file, not a folder: give a folder name")
    for source in inputs:
        if Path(source).resolve().is_relative_to(folder.resolve()):
            raise OutputError(
                f"{folder}: holds the input file '{source}': write into another folder "
                "(--force never overwrites an input)"
            )
    if folder.exists():
        present = sorted(p.name for p in folder.iterdir())
        if present and not force:
            raise OutputError(
                f"{folder}: is not empty (has '{present[0]}'): write into a new or empty "
                "folder, or give --force to overwrite the files of the same name"
            )
        check_folder(folder, folder)
    else:
        parent = folder.parent
        while not parent.exists():
            parent = parent.parent
        check_folder(parent, folder)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_write(path: Path, *, replace: bool = False) -> Iterator[Path]:
    """Yield a temporary path in ``path``'s folder; rename it to ``path`` once written.

    The temporary file keeps ``path``'s suffix (writers that choose the format
    by suffix see the right one). Without ``replace``, an existing ``path`` is
    never overwritten (the rename is a hard link, which fails if the name
    exists). On an error, Ctrl-C or SIGTERM (the command line turns it into an
    exception) the temporary file is removed and ``path`` is untouched (a press that an
    extension swallowed, counted by the command line, too); the
    temporaries of a killed run are removed when the folder is written next
    (:mod:`wheelload.models.runtime.temporaries`).
    """
    path = Path(path)
    check_folder(path.parent, path)
    temporary = temporary_file(path.parent, path.stem, path.suffix)
    try:
        os.chmod(temporary, 0o666 & ~_umask())
        yield temporary
        interrupts.check()  # a Ctrl-C an extension swallowed while writing: no output
        if replace:
            os.replace(temporary, path)
        else:
            try:
                os.link(temporary, path)
            except FileExistsError:
                raise OutputError(
                    f"{path}: appeared while writing: choose another name or give --force"
                ) from None
            except OSError:  # no hard links on this file system
                if path.exists():
                    raise OutputError(f"{path}: exists: give --force to replace it") from None
                os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def write_text(path: Path, text: str, *, replace: bool = False) -> None:
    """Write UTF-8 ``text`` to ``path`` through :func:`atomic_write`."""
    with atomic_write(path, replace=replace) as temporary:
        temporary.write_text(text, encoding="utf-8")


def _write_options(schema):
    """CSV options: quote only text columns and names that need it (as ``to_csv``)."""
    import pyarrow as pa
    import pyarrow.csv as pc

    text = any(pa.types.is_string(f.type) or pa.types.is_large_string(f.type) for f in schema)
    plain = all(not set(f.name) & set(',"\r\n') for f in schema)
    return pc.WriteOptions(
        quoting_style="needed" if text else "none", quoting_header="none" if plain else "needed"
    )


def _arrow_array(values):
    """A pyarrow array viewing a 1-D numpy array (no copy; ``pa.array`` would import pandas)."""
    import numpy as np
    import pyarrow as pa

    values = np.ascontiguousarray(values)
    kind = pa.from_numpy_dtype(values.dtype)
    return pa.Array.from_buffers(kind, len(values), [None, pa.py_buffer(values)])


class _WriterThread:
    """Writes record batches on a thread of its own, while the caller computes the next chunk.

    pyarrow formats and writes with the GIL released, so the CSV's number
    formatting overlaps the compiled loop. At most one batch waits (memory: one
    chunk more). An error of the writer is raised in the caller at its next
    ``put`` or at ``close``.
    """

    _DONE = object()

    def __init__(self, temporary: Path, fmt: TableFormat) -> None:
        import queue
        import threading

        self.temporary, self.fmt = temporary, fmt
        self.batches: queue.Queue = queue.Queue(maxsize=1)
        self.error: BaseException | None = None
        self.abort = False
        self.thread = threading.Thread(target=self._run, name="table-writer", daemon=True)
        self.thread.start()

    def _open(self, schema):
        if self.fmt is TableFormat.PARQUET:
            import pyarrow.parquet as pq

            return pq.ParquetWriter(str(self.temporary), schema)
        import pyarrow.csv as pc

        return pc.CSVWriter(str(self.temporary), schema, write_options=_write_options(schema))

    def _run(self) -> None:
        writer = None
        try:
            while (batch := self.batches.get()) is not self._DONE:
                if self.error is None and not self.abort:
                    try:
                        if writer is None:
                            writer = self._open(batch.schema)
                        writer.write_batch(batch)
                    except BaseException as error:  # handed to the caller, raised there
                        self.error = error
        finally:
            if writer is not None:
                try:
                    writer.close()
                except BaseException as error:
                    self.error = self.error or error

    def put(self, batch) -> None:
        self._raise()
        self.batches.put(batch)

    def close(self, *, abort: bool) -> None:
        """Wait for the last batch to be written (``abort``: drop the ones waiting)."""
        self.abort = abort
        self.batches.put(self._DONE)
        self.thread.join()
        if not abort:
            self._raise()

    def _raise(self) -> None:
        if self.error is not None:
            raise self.error


@contextlib.contextmanager
def table_writer(path: Path, *, replace: bool = False) -> Iterator:
    """Yield ``write(columns)``, which appends a chunk of named columns to a table file.

    CSV or Parquet by ``path``'s suffix, written by pyarrow (CSV floats in
    shortest round-trip form: a read gives back the same doubles) on a thread
    of its own, overlapping the caller's work, into a temporary file renamed into
    place by :func:`atomic_write` once the last chunk is in. Every chunk must
    have the same columns and types; its arrays are written without a copy and
    must not be changed after ``write`` returns.

    Example
    -------
    >>> with table_writer(Path("loads.parquet")) as write:
    ...     for chunk in chunks:
    ...         write({"t": chunk.t, "fz_fl": chunk.fz_fl})
    """
    import pyarrow as pa

    fmt = table_format(Path(path))
    with atomic_write(Path(path), replace=replace) as temporary:
        writer = _WriterThread(temporary, fmt)
        schema = None

        def write(columns: dict) -> None:
            nonlocal schema
            arrays = [_arrow_array(values) for values in columns.values()]
            batch = pa.RecordBatch.from_arrays(arrays, names=list(columns))
            schema = schema or batch.schema
            if not batch.schema.equals(schema):  # pyarrow's writers do not check it
                raise OutputError(
                    f"{path}: a chunk's columns ({', '.join(batch.schema.names)}) differ from "
                    f"the first chunk's schema ({', '.join(schema.names)}): write one table "
                    "per set of columns"
                )
            writer.put(batch)

        try:
            yield write
        except BaseException:
            writer.close(abort=True)
            raise
        writer.close(abort=False)


def write_frame(frame, path: Path, *, replace: bool = False) -> None:
    """Write a DataFrame as CSV or Parquet (by suffix) with pyarrow, through :func:`atomic_write`.

    Same columns and values as ``to_csv``/``to_parquet`` (index left out); a
    read with ``pandas.read_csv`` or ``read_parquet`` gives back the same numbers.
    """
    import pyarrow as pa

    fmt = table_format(Path(path))
    table = pa.Table.from_pandas(frame, preserve_index=False)
    with atomic_write(Path(path), replace=replace) as temporary:
        if fmt is TableFormat.PARQUET:
            import pyarrow.parquet as pq

            pq.write_table(table, str(temporary))
        else:
            import pyarrow.csv as pc

            pc.write_csv(table, str(temporary), write_options=_write_options(table.schema))
