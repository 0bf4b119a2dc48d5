"""Ctrl-C presses the console command has seen (:mod:`wheelload.studies.cli` counts them).

CasADi's evaluation checks for signals and may swallow the KeyboardInterrupt its check
raised: the call then returns as if nothing happened, or hands back what then fails
(``None`` for an array). Loops over CasADi calls ask :func:`check` between calls, and the
command reports an error after a press as the interruption it is.
"""

from __future__ import annotations

_pressed = 0


def handler(signum, frame) -> None:
    """SIGINT: counted, then raised as Python's default handler raises it."""
    global _pressed
    _pressed += 1
    raise KeyboardInterrupt


def pressed() -> int:
    """Presses since :func:`reset`."""
    return _pressed


def reset() -> None:
    global _pressed
    _pressed = 0


def check() -> None:
    """KeyboardInterrupt if Ctrl-C was pressed (a press an extension swallowed included)."""
    if _pressed:
        raise KeyboardInterrupt
