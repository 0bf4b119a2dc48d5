"""Checks of one vehicle-file section's values: each error names the offending key.

A section's ``_check`` raises :class:`SectionKeyError` with the key; the reader
prefixes the section path and the file name (``wheelload.models.vehicle.description``).
"""

from __future__ import annotations


class SectionKeyError(ValueError):
    """A value of a section out of its range: carries the key it names."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key


def require_positive(section: object, key: str) -> None:
    """Raise unless ``section.key > 0``."""
    if not getattr(section, key) > 0.0:
        raise SectionKeyError(key, f"must be > 0, got {getattr(section, key)}")


def require_non_negative(section: object, key: str) -> None:
    """Raise unless ``section.key >= 0``."""
    if not getattr(section, key) >= 0.0:
        raise SectionKeyError(key, f"must be >= 0, got {getattr(section, key)}")


def require_share(section: object, key: str) -> None:
    """Raise unless ``0 <= section.key <= 1``."""
    if not 0.0 <= getattr(section, key) <= 1.0:
        raise SectionKeyError(key, f"must be in [0, 1], got {getattr(section, key)}")
