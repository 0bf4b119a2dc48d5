"""Scenario settings (:mod:`wheelload.studies.drive.scenarios`), recorded in the log metadata."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, kw_only=True)
class Options:
    """Scenario settings recorded in the log metadata."""

    roughness: str | None = None  # ISO 8608 class A-D, or None for a smooth road
    seed: int = 0
    min_wavelength: float = 1.6  # m, bounce-sweep only
    shorten: float = 1.0  # fraction of a lap to drive (tests); 1 = full lap
    grade: float = 0.0  # standstill only: rise over run, > 0 uphill
    bank: float = 0.0  # standstill only: rise over run, > 0 left edge higher
