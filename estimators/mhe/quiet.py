"""Silence what the OSQP extension prints to standard output.

OSQP prints "Polishing not needed ..." whatever its ``verbose`` setting;
its Python extension writes through Python's ``sys.stdout``
(``PySys_WriteStdout``), so replacing ``sys.stdout`` for the call keeps it
out of tables that commands print for users to parse.

Example
-------
>>> with quiet_stdout(polish):  # polishing prints; a solve without it does not
...     solver.solve()
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Iterator


@contextlib.contextmanager
def quiet_stdout(when: bool = True) -> Iterator[None]:
    """Discard everything written to ``sys.stdout`` inside the block (only ``when`` true)."""
    if not when:
        yield
        return
    with contextlib.redirect_stdout(io.StringIO()):
        yield
