"""Local worker processes leave Ctrl-C to the command that started them.

A terminal's Ctrl-C reaches every process of the foreground group. A worker
that took it would print its own ``KeyboardInterrupt`` traceback; with
:func:`ignore_interrupts` as the pool's initializer it finishes its task (its
files are written through temporaries renamed into place), while the command
cancels the tasks not started and prints one line (:mod:`wheelload.studies.cli`).

Example
-------
>>> pool = ProcessPoolExecutor(max_workers=2, initializer=ignore_interrupts)
"""

from __future__ import annotations

import signal


def ignore_interrupts() -> None:
    """Ignore SIGINT in this (worker) process."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
