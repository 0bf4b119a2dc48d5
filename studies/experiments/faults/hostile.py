"""Hostile logs and the estimators' behaviour on them (issue 21, items 1-5).

A hostile log is a plant log whose every input channel, optional ones
included, is corrupted at a fraction of its samples by NaN, :math:`\\pm 10^{30}`
or a spike of 10 to 1000 times the channel's clean spread (added to the
sample). The body-rate derivatives are written as columns, derived from the
clean rates by the Python reader's estimator, so that the Python filter and the
generated C's example program (which reads them where a log has them) read the
same inputs, and are corrupted like the other channels.

:func:`summarise` gives what ``wheelload bench hostile`` prints per estimator:
non-finite outputs, max :math:`|F_z|`, steps locked out (``STEP_REJECTED``
with a valid interval) and, for the C, the sanitizer reports of a build with
``-fsanitize=address,undefined``.
"""

from __future__ import annotations

import dataclasses
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators import StepFlag
from wheelload.estimators.logs.signals import rate_derivatives
from wheelload.models import INPUTS
from wheelload.models.conventions import WHEELS

#: The C compilers' sanitizer flags of the hostile builds.
SANITIZE = ("-fsanitize=address,undefined", "-fno-omit-frame-pointer")
#: Lines by which AddressSanitizer and UndefinedBehaviorSanitizer report a finding.
SANITIZER_MARKS = ("runtime error:", "ERROR: AddressSanitizer", "ERROR: LeakSanitizer")
LOADS = [f"fz_{w}" for w in WHEELS]
HUGE = 1e30


def with_rate_derivatives(frame: pd.DataFrame, signals) -> pd.DataFrame:
    """``frame`` with columns ``wx_dot wy_dot wz_dot`` from ``signals``' rates (if missing)."""
    frame = frame.copy()
    if "wx_dot" not in frame and signals.rates is not None:
        derived = rate_derivatives(signals)
        for i, name in enumerate(("wx_dot", "wy_dot", "wz_dot")):
            frame[name] = derived[:, i]
    return frame


def hostile_frame(frame: pd.DataFrame, fraction: float, seed: int) -> pd.DataFrame:
    """A copy of ``frame`` with every input channel corrupted at ``fraction`` of its samples.

    Each corrupted sample is, with equal chance, NaN, +1e30, -1e30 or the
    sample plus a spike of 10-1000 times the channel's standard deviation
    (random sign). Reference loads and ``t`` are untouched.
    """
    if not 0.0 < fraction <= 1.0:
        raise ValueError(f"fraction must be in (0, 1], got {fraction}")
    rng = np.random.default_rng(seed)
    hostile = frame.copy()
    for name in (column for column in INPUTS if column in frame):
        values = hostile[name].to_numpy(dtype=float).copy()
        spread = float(np.nanstd(values)) or 1.0
        rows = np.flatnonzero(rng.random(len(values)) < fraction)
        kind = rng.integers(0, 4, rows.size)
        spike = rng.choice([-1.0, 1.0], rows.size) * spread * 10.0 ** rng.uniform(1, 3, rows.size)
        values[rows] = np.select(
            [kind == 0, kind == 1, kind == 2],
            [np.nan, HUGE, -HUGE],
            values[rows] + spike,
        )
        hostile[name] = values
    return hostile


@dataclass(frozen=True, kw_only=True)
class HostileSummary:
    """What one estimator did on a hostile log."""

    name: str
    sanitizer_reports: int | None  # None: not built with the sanitizers
    non_finite: int  # output values (loads, std) that are not finite
    max_load: float  # N, largest |Fz|
    locked_out: int  # steps rejected although their interval was valid

    def row(self, weight: float) -> list[str]:
        reports = "n/a" if self.sanitizer_reports is None else str(self.sanitizer_reports)
        bound = "yes" if self.max_load <= 2.0 * weight else "NO"
        return [
            self.name, reports, str(self.non_finite), f"{self.max_load:.0f}", bound,
            str(self.locked_out),
        ]  # fmt: skip


def summarise(name: str, loads, std, flags, sanitizer_reports: int | None) -> HostileSummary:
    """Counts of :class:`HostileSummary` from an estimator's outputs (the log's ``t`` valid)."""
    loads, std = np.asarray(loads, float), np.asarray(std, float)
    finite = np.isfinite(loads).all(axis=1)
    return HostileSummary(
        name=name,
        sanitizer_reports=sanitizer_reports,
        non_finite=int(np.count_nonzero(~np.isfinite(loads)) + np.count_nonzero(~np.isfinite(std))),
        max_load=float(np.max(np.abs(loads[finite]))) if finite.any() else float("inf"),
        locked_out=int(np.count_nonzero(np.asarray(flags, np.int64) & StepFlag.STEP_REJECTED)),
    )


def sanitizer_reports(stderr: str) -> int:
    """Number of findings the sanitizers printed."""
    return sum(stderr.count(mark) for mark in SANITIZER_MARKS)


def run_binary(command: list[str]) -> subprocess.CompletedProcess:
    """Run a sanitized program; its findings are on stderr (no leak check: one-shot tools)."""
    env = {"ASAN_OPTIONS": "detect_leaks=0:abort_on_error=0", "UBSAN_OPTIONS": "print_stacktrace=0"}
    return subprocess.run(command, capture_output=True, text=True, timeout=600, env=env)


def write_frame(frame: pd.DataFrame, path: Path) -> Path:
    """``frame`` as a CSV log the C example reads (NaN as an empty field)."""
    frame.to_csv(path, index=False, na_rep="", float_format="%.17g")
    return path


def with_inputs(signals, frame: pd.DataFrame):
    """``signals`` with the input channels of ``frame`` (same rows)."""
    rates = frame[["wx", "wy", "wz"]].to_numpy(float) if "wx" in frame else signals.rates
    dots = frame[["wx_dot", "wy_dot", "wz_dot"]].to_numpy(float) if "wx_dot" in frame else None
    hub = [f"az_{w}" for w in WHEELS]
    return dataclasses.replace(
        signals,
        d=frame[[f"d_{w}" for w in WHEELS]].to_numpy(float),
        v=frame[[f"v_{w}" for w in WHEELS]].to_numpy(float),
        acc=frame[["ax", "ay", "az"]].to_numpy(float),
        vx=frame["vx"].to_numpy(float),
        rates=rates,
        rate_dots=dots,
        hub=frame[hub].to_numpy(float) if hub[0] in frame else signals.hub,
    )


def white_noise_signals(vehicle, base, seed: int, settings=None):
    """``base`` with travels, rates, specific force and speed white noise over their whole
    plausible ranges (:class:`~wheelload.estimators.GuardSettings`), uniform.

    Every sample passes the plausibility check; together they are nothing a car
    does, which is what the envelope property is about.
    """
    from wheelload.estimators import GuardSettings
    from wheelload.models import GRAVITY

    g = settings or GuardSettings()
    rng = np.random.default_rng(seed)
    n = len(base.t)
    weight = vehicle.mass.total * GRAVITY
    springs = np.array(
        [vehicle.suspension.front.spring_rate] * 2 + [vehicle.suspension.rear.spring_rate] * 2
    )
    uniform = lambda shape, bound: rng.uniform(-1.0, 1.0, shape) * bound  # noqa: E731
    return dataclasses.replace(
        base,
        d=uniform((n, 4), g.travel_range * weight / springs),
        v=uniform((n, 4), g.max_travel_rate),
        acc=uniform((n, 3), g.max_acceleration * GRAVITY),
        vx=uniform(n, g.max_speed),
    )


def total_envelope(kf, signals) -> tuple[float, float]:
    r"""The log's own range of the total load: the equilibrium's vertical row
    :math:`b_0 = \sum F_z` (eq. 15, with every term the log's channels allow) over all
    samples, and the weight (the filter starts at the static loads).

    An independent evaluation of :func:`wheelload.models.equilibrium_function`
    on the log's inputs (missing channels gate their terms off), not the filter's.
    """
    from wheelload.estimators.logs.inputs import input_matrix
    from wheelload.models import equilibrium_function, gates_function

    u = input_matrix(signals)
    valid = np.isfinite(u).astype(float)
    n = u.shape[1]
    gates = gates_function().map(n)(valid, kf.p)[0]
    _, b = equilibrium_function().map(n)(np.where(valid > 0, u, 0.0), gates, kf.p)
    vertical = np.asarray(b)[0]
    weight = float(np.sum(kf.parameters.static()))
    return min(vertical.min(), weight), max(vertical.max(), weight)


def envelope_excess(kf, signals, loads) -> float:
    """How far [N] the total of ``loads`` leaves :func:`total_envelope` (0 if inside)."""
    low, high = total_envelope(kf, signals)
    total = np.asarray(loads).sum(axis=1)
    return float(max(np.max(total - high), np.max(low - total), 0.0))
