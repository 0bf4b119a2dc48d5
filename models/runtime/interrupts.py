"""Ctrl-C presses the console command has seen (:mod:`wheelload.studies.cli` counts them).

CasADi's evaluation checks for signals and may swallow the KeyboardInterrupt its check
raised: the call then returns as if nothing happened, or hands back what then fails
(``None`` for an array). Loops over CasADi calls ask :func:`check` between calls, and the
command reports an error after a press as the interruption it is. OSQP's solve catches
SIGINT with a handler of its own and returns the status "interrupted" (Python's handler
never runs): the MHE hands that press on through :func:`caught`.

The counter lives here, below the studies, so that the estimators' loops can ask it too.
"""

from __future__ import annotations

import signal

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


def caught() -> None:
    """KeyboardInterrupt for a press a C library's own handler caught: counted where
    :func:`handler` counts presses (the console command), then raised."""
    global _pressed
    if signal.getsignal(signal.SIGINT) is handler:
        _pressed += 1
    raise KeyboardInterrupt
