r"""Methods whose loads are identical on a log, shown once in tables and figures.

Two methods are identical when their loads differ by less than :data:`TOLERANCE` at every
sample and wheel, :math:`\max_{k,i} |F^a_{z,ki} - F^b_{z,ki}| <` 1e-9 N: a thousand times the
rounding of a 4 kN load in double precision (4e3 × 2.2e-16 ≈ 1e-12 N), a millionth of
the smallest error any method makes. Tables and figures then show one row or line named
``a = b`` and a note saying why (:func:`identity_notes`).

The known case: ``projection-mp`` and ``projection-ls`` (Simon & Chia 2002). With the
vehicle files' tuning every wheel has the same process and suspension noise, so while
all four suspension rows are used the covariance before the projection is
:math:`P = p I`; then :math:`W = P^{-1} = I / p` and :math:`W = I` give the same
projection :math:`\hat x + W^{-1} A^\top (A W^{-1} A^\top)^{-1} (b - A \hat x)`. A log with
a missing or gated travel breaks :math:`P \propto I` and the two part again, so the
collapse is decided on each log's loads, never by name.

Example
-------
>>> groups = identical_groups({"kf": kf.loads, "projection-mp": mp.loads, ...})
>>> collapse(metrics, groups)  # {"kf": ..., "projection-mp = projection-ls": ...}
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TypeVar

import numpy as np

#: Largest ``|difference|`` [N] of two methods' loads that still counts as identical.
TOLERANCE = 1e-9
#: Why a known pair is identical (the members in registry order).
REASONS = {
    ("projection-mp", "projection-ls"): (
        "with this tuning P ∝ I before the projection (equal noise on the four wheels, "
        "every suspension row used), so W = P⁻¹ and W = I project alike"
    ),
}

Value = TypeVar("Value")


def max_difference(a: np.ndarray, b: np.ndarray) -> float:
    """:math:`\\max |a - b|` [N]; infinite for arrays of different shapes."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        return float("inf")
    return float(np.max(np.abs(a - b), initial=0.0))


def identical_groups(
    loads: Mapping[str, np.ndarray], tolerance: float = TOLERANCE
) -> tuple[tuple[str, ...], ...]:
    """The methods grouped by identical loads (each group in ``loads`` order, one member
    for a method like no other); a method joins the first group whose first member it
    matches within ``tolerance`` [N]."""
    groups: list[list[str]] = []
    for name, values in loads.items():
        for group in groups:
            if max_difference(loads[group[0]], values) < tolerance:
                group.append(name)
                break
        else:
            groups.append([name])
    return tuple(tuple(group) for group in groups)


def label(group: tuple[str, ...]) -> str:
    """A group's name in tables and figures: ``projection-mp = projection-ls``."""
    return " = ".join(group)


def collapse(values: Mapping[str, Value], groups: tuple[tuple[str, ...], ...]) -> dict[str, Value]:
    """``values`` in order, a group's first member under the group's :func:`label`, its
    other members left out; a name in no group is kept as it is."""
    first = {group[0]: group for group in groups}
    later = {name for group in groups for name in group[1:]}
    return {
        label(first[name]) if name in first else name: value
        for name, value in values.items()
        if name not in later
    }


def identity_notes(
    loads: Mapping[str, np.ndarray], groups: tuple[tuple[str, ...], ...]
) -> tuple[str, ...]:
    """One line per group of two or more: the members are identical, by how much, why."""
    stored = any(np.asarray(values).dtype == np.float32 for values in loads.values())
    resolution = ", compared as stored (float32)" if stored else ""
    notes = []
    for group in groups:
        if len(group) < 2:
            continue
        largest = max(max_difference(loads[group[0]], loads[name]) for name in group[1:])
        reason = REASONS.get(group, "their loads agree at every sample")
        notes.append(
            f"{label(group)}: identical on this log, max |difference| {largest:.1e} N "
            f"< {TOLERANCE:g} N{resolution}; {reason}"
        )
    return tuple(notes)
