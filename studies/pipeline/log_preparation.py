"""What runs between reading a log and estimating it, the same on every path of ``estimate``.

The wiring checks and their plausibility companion (refusing a log whose sensors are
wired or scaled wrong), the static loads measured from the log (corner weights, a
still period: :mod:`~wheelload.studies.pipeline.measured_static`) and the payload's
travel reference, each with the note it gives the user. The whole-log path
(:mod:`~wheelload.studies.pipeline.batch`) and the chunked lean path
(:mod:`~wheelload.studies.pipeline.lean_estimate`) differ only in where the signals come
from: the whole log, or the scan's head and wiring window.

Example
-------
>>> prepared = prepare_log(vehicle, settings, source=signals.source,
...     wiring_report=lambda: check_wiring(...), checked_signals=lambda: signals,
...     static_loads=lambda vehicle: measured_static_loads(signals, vehicle, settings))
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from wheelload.models import Vehicle
from wheelload.studies.pipeline.measured_static import payload_reference
from wheelload.studies.pipeline.run_messages import log_checks, log_vehicle, phase

logger = logging.getLogger(__name__)

if TYPE_CHECKING:
    from wheelload.estimators import Signals
    from wheelload.estimators.logs.checks import WiringReport


@dataclass(frozen=True, kw_only=True)
class PreparedLog:
    """A log ready to estimate: the vehicle it runs on, its static loads, the notes."""

    vehicle: Vehicle  # the description, with the payload's travel reference set
    static: np.ndarray | None  # static loads FL..RR [N] measured from the log, if any
    notes: tuple[str, ...]  # what the checks and the static loads tell the user


def prepare_log(
    vehicle: Vehicle,
    settings,
    *,
    source: str,
    wiring_report: Callable[[], WiringReport],
    checked_signals: Callable[[], Signals],
    static_loads: Callable[[Vehicle], tuple[np.ndarray | None, list[str]]],
    notes: tuple[str, ...] = (),
) -> PreparedLog:
    """The checks, the static loads and the payload reference of one log, in that order.

    With ``settings.wiring_checks`` (an
    :class:`~wheelload.studies.pipeline.log_settings.EstimateSettings`) the wiring report
    and the plausibility of ``checked_signals()`` against ``vehicle`` are checked, a
    failure raised naming ``source``; then ``static_loads(vehicle)`` and
    :func:`~wheelload.studies.pipeline.measured_static.payload_reference`. ``notes`` come
    first (what reading the log found).
    """
    from wheelload.estimators.logs.checks import describe, raise_for_wiring
    from wheelload.estimators.logs.plausibility import (
        check_plausibility,
        describe_plausibility,
        raise_for_plausibility,
    )

    told = list(notes)
    log_vehicle(settings.vehicle, vehicle)
    with phase("checks"):
        if settings.wiring_checks:
            report = wiring_report()
            log_checks("wiring", report)
            raise_for_wiring(report, source)
            told.append(describe(report))
            plausibility = check_plausibility(checked_signals(), vehicle)
            log_checks("plausibility", plausibility)
            raise_for_plausibility(plausibility, source)
            told.append(describe_plausibility(plausibility))
        else:
            logger.info("wiring and plausibility checks skipped (--skip-wiring-checks)")
    static, reasons = static_loads(vehicle)
    told += reasons
    vehicle, reasons = payload_reference(vehicle, settings)
    told += reasons
    return PreparedLog(vehicle=vehicle, static=static, notes=tuple(told))
