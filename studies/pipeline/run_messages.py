"""What a run tells at ``-v`` and ``-vv``: what was read, what was derived, each check's
numbers and the time of each phase, through :mod:`logging` (the console command sets the
level: ``-q`` errors only, default warnings, ``-v`` info, ``-vv`` debug).

At ``-v`` (INFO): the log read (file, rows, rate, the channels found and those derived:
travel rates from the travel, ``vx`` from the wheel speeds, ``az`` assumed ``g``), the
vehicle file and its car, the channel map, and one line per phase with its wall time
(read, checks, filter, write). At ``-vv`` (DEBUG): every wiring and plausibility check
with its statistic and outcome.

Example
-------
>>> with phase("filter"):
...     estimate = kf.run(signals)
INFO: filter: 0.21 s
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

logger = logging.getLogger("wheelload.run")

#: The travel, travel-rate and reference channels, wheel order FL, FR, RL, RR.
_CORNERS = ("fl", "fr", "rl", "rr")


@contextlib.contextmanager
def phase(name: str) -> Iterator[None]:
    """Log ``NAME: SECONDS s`` at INFO when the block ends (also when it raises)."""
    start = time.perf_counter()
    try:
        yield
    finally:
        logger.info("%s: %.3f s", name, time.perf_counter() - start)


def channels_found(
    *,
    travel_present: np.ndarray,
    velocities_derived: bool,
    az_assumed: bool,
    speed_source,
    rates: bool,
    reference: np.ndarray | None,
) -> tuple[str, str]:
    """The channels a log gave and those derived, each in words: ``(found, derived)``."""
    travel = [f"d_{w}" for w, on in zip(_CORNERS, np.asarray(travel_present)) if on]
    found = list(travel)
    derived = []
    if velocities_derived:
        derived.append("v_* (travel rates) from d_* by the first-order derivative filter")
    elif travel:
        found.append("v_*")
    found += ["ax", "ay"]
    if az_assumed:
        derived.append("az assumed g (no az channel)")
    else:
        found.append("az")
    source = getattr(speed_source, "value", str(speed_source))
    if source == "logged":
        found.append("vx")
    else:
        derived.append(f"vx: {source}")
    if rates:
        found.append("wx wy wz")
    if reference is not None:
        found += [f"fz_{w}" for w, on in zip(_CORNERS, np.asarray(reference)) if on]
    return " ".join(found), "; ".join(derived) or "nothing"


def log_read(
    source: str | Path, rows: int, rate: float, found: str, derived: str, channels=None
) -> None:
    """The ``-v`` lines of one log read: rows, rate, channels found and derived, the map."""
    logger.info("read %s: %d rows at %.4g Hz", source, rows, rate)
    logger.info("channel map: %s", channels if channels else "none (the log's own names)")
    logger.info("channels found: %s", found)
    logger.info("derived: %s", derived)


def log_signals(signals, channels=None) -> None:
    """:func:`log_read` for a log read whole (an :class:`~wheelload.estimators.Signals`)."""
    if not logger.isEnabledFor(logging.INFO):
        return
    reference = None
    if signals.reference is not None:
        reference = np.isfinite(signals.reference).any(axis=0)
    found, derived = channels_found(
        travel_present=signals.travel_present,
        velocities_derived=signals.velocities_derived,
        az_assumed=signals.az_assumed,
        speed_source=signals.speed_source,
        rates=signals.rates is not None,
        reference=reference,
    )
    rate = signals.sample_rate if len(signals) > 1 else float("nan")
    log_read(signals.source, len(signals), rate, found, derived, channels)


def log_stream(stream) -> None:
    """:func:`log_read` for a scanned log (a :class:`~wheelload.estimators.LogStream`)."""
    if not logger.isEnabledFor(logging.INFO):
        return
    found, derived = channels_found(
        travel_present=stream.travel_present,
        velocities_derived=stream.velocities_derived,
        az_assumed=stream.az_assumed,
        speed_source=stream.speed_source,
        rates=any(name in stream.names for name in ("wx", "wy", "wz")),
        reference=stream.reference_present,
    )
    log_read(stream.source, len(stream), stream.sample_rate, found, derived)


def log_vehicle(path: str | Path, vehicle) -> None:
    """The ``-v`` line naming the vehicle file and its car."""
    logger.info("vehicle file %s: '%s', %.1f kg", path, vehicle.name, float(vehicle.mass.total))


def log_checks(kind: str, report) -> None:
    """The ``-vv`` lines of a check report: each check's statistic, outcome and note."""
    for check in report.checks:
        logger.debug(
            "%s check '%s': statistic %.4g, %s%s",
            kind,
            check.name,
            check.statistic,
            check.outcome.value if hasattr(check.outcome, "value") else check.outcome,
            f" ({check.note})" if check.note else "",
        )


def log_vehicle_ranges(vehicle) -> None:
    """The ``-vv`` lines of a vehicle file's range checks: each key's value against its
    accepted interval (:data:`~wheelload.models.vehicle.plausibility.RANGES`)."""
    if not logger.isEnabledFor(logging.DEBUG):
        return
    from wheelload.models.vehicle.plausibility import range_checks

    for name, value, accepted in range_checks(vehicle):
        outcome = "passed" if accepted.holds(value) else "outside"
        logger.debug(
            "range check '%s' = %.4g in [%.4g, %.4g]: %s (%s)",
            name, value, accepted.low, accepted.high, outcome, accepted.reason,
        )  # fmt: skip


def log_vehicle_terms(vehicle) -> None:
    """The ``-v`` line of the model terms a vehicle file switches on and off."""
    model = getattr(vehicle, "model", None)
    if model is None or not logger.isEnabledFor(logging.INFO):
        return
    import dataclasses

    flags = {f.name: getattr(model, f.name) for f in dataclasses.fields(model)}
    on = [name for name, value in flags.items() if value is True]
    off = [name for name, value in flags.items() if value is False]
    logger.info("model terms on: %s; off: %s", ", ".join(on) or "none", ", ".join(off) or "none")
