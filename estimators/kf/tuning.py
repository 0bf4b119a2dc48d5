r"""The two-stage KF's tuning vector: noise densities, nominal interval, guard settings and
the reported-sigma coefficients (:mod:`.reported_std`, last).

Tuning is per second (white-noise densities): :math:`Q = q\,dt\,I`,
:math:`R_s = r_s/\Delta t_{nom}\,I`, :math:`R_c = \mathrm{diag}(r_c)/\Delta t_{nom}` with the
log's nominal (median) interval (:func:`nominal_interval`), so that a gap grows the covariance
and never shrinks the measurement noise (Siegloff & Choi §III, eq. 19-25). The vector is a
runtime input of the step Function and of the generated C, in :data:`TUNING` order.

Example
-------
>>> tuning = tuning_vector(load_vehicle("sports_car.toml"), nominal_interval(signals.t))
"""

from __future__ import annotations

import dataclasses

import numpy as np

from wheelload.estimators.guards.settings import GuardSettings, guard_settings_for
from wheelload.estimators.kernels import order_statistics
from wheelload.estimators.kernels.layout import Domain, Field, Layout
from wheelload.estimators.types import step_blocks
from wheelload.models import Vehicle
from wheelload.models.input_validity import MAX_INTERVAL
from wheelload.models.vehicle.description import SIGMA_KEYS, FaultTuning


def _filter(key: str, unit: str, doc: str = "", parts: tuple[str, ...] = ()) -> Field:
    """An entry the vehicle file's ``[filter]`` gives under its own name."""
    return Field(key, unit=unit, file_key=("filter", key), doc=doc, parts=parts)


def _payload(key: str, unit: str, parts: tuple[str, ...] = ()) -> Field:
    """An entry of the vehicle file's ``[filter.payload]`` (payload filter, :mod:`.payload`)."""
    return Field(f"payload_{key}", unit=unit, file_key=("filter", "payload", key), parts=parts)


def _rows(stem: str, suffix: str = "") -> tuple[str, ...]:
    """Per equilibrium row (vertical, pitch, roll) the entry's name."""
    return tuple(f"{stem}_{row}{suffix}" for row in ("vertical", "pitch", "roll"))


_FAULT_KEYS = {f.name for f in dataclasses.fields(FaultTuning)}
#: Largest value a tuning entry may take (``PREFIX_set_param`` and ``PREFIX_init`` of the
#: generated C): its square stays finite in float; and the smallest of a positive one (a
#: denormal divisor would make the step's arithmetic overflow).
LARGEST = 1e15
SMALLEST = 1e-9
#: The values each tuning entry may take, where not ``(0, LARGEST]``.
_DOMAINS = {
    # The constant densities: a 1-sigma of 0.01 N at 100 Hz at least (a calibrated R of 0
    # holds the loads on the gate; Q of 0 stops the filter learning). Q has no upper bound:
    # the covariance ceiling holds any (guards/limits.py).
    "process_noise_density": Domain(1e-6),
    **dict.fromkeys(
        ("suspension_noise_density", "constraint_noise_density"), Domain(1e-6, LARGEST)
    ),  # fmt: skip
    "sample_interval": Domain(1e-6, 1e3),  # s: 1 MHz to one sample in 17 minutes
    "interval_band": Domain(1.0, 1e3, open_low=True),
    "isolation_fraction": Domain(0.0, 1.0, open_low=True, open_high=True),
    "covariance_floor": Domain(0.0, 1e6, open_low=True),  # N
    "payload_estimate": Domain(0.0, 1.0),
    "payload_position_std": Domain(0.0, LARGEST),  # 0: that coordinate not estimated
}


def _domain(field: Field) -> Field:
    """``field`` with its domain: :data:`_DOMAINS`; ``[0, LARGEST]`` for an input-dependent
    density or a reported-sigma coefficient (0 leaves its term out); else
    ``[SMALLEST, LARGEST]``."""
    if field.name in _DOMAINS:
        domain = _DOMAINS[field.name]
    elif field.name.startswith("sigma_") or field.name.endswith(
        ("_rate_density", "_hub_density", "_acceleration_density")
    ):
        domain = Domain(0.0, LARGEST)
    else:
        domain = Domain(SMALLEST, LARGEST)
    return dataclasses.replace(field, domain=domain)


#: The tuning vector, in order: each entry's name, unit, vehicle-file key and domain.
TUNING = Layout(
    "tuning",
    map(_domain, (
        _filter("process_noise_density", "N^2/s", "Q = q dt I"),
        _filter("suspension_noise_density", "N^2 s", "R_s = r_s / dt I"),
        _filter("constraint_noise_density", "N^2 s, N^2 m^2 s, N^2 m^2 s",
                "R_c = diag(r_c) / dt", _rows("constraint_noise")),
        Field("sample_interval", unit="s", doc="the log's nominal (median) interval"),
        *[
            Field(name, file_key=("filter", "faults", name) if name in _FAULT_KEYS else None,
                  doc="guard setting (kf.guard.GuardSettings, unit there)")
            for name in GuardSettings.names()
        ],
        _filter("suspension_noise_rate_density", "N^2 s/(m/s)^2", "R_s + this v^2 / dt"),
        _filter("suspension_noise_hub_density", "N^2 s/(m/s^2)^2",
                "R_s + this (a_hub - az)^2 / dt"),
        _filter("constraint_noise_acceleration_density", "N^2 s/(m/s^2)^2, N^2 m^2 s/(m/s^2)^2",
                "R_c + this ((az - g)^2, ax^2, ay^2) / dt",
                _rows("constraint_noise", "_acceleration")),
        # The payload filter's entries; estimate: 1 where the file estimates the payload
        # (estimate and travel_from_reference).
        _payload("estimate", ""),
        _payload("mass_std", "kg"),
        _payload("position_std", "m", tuple(f"payload_position_std_{a}" for a in "xyz")),
        _payload("residual_density", "N^2 s, N^2 m^2 s", _rows("payload_residual_density")),
        _payload("drift_density", "kg^2/s"),
        _payload("standstill_density", "kg^2/s"),
        _payload("standstill_speed", "m/s"),
        _payload("gate", ""),
        _payload("acceleration_scale", "m/s^2", _rows("payload_acceleration_scale")),
        _payload("apparent_mass", "kg"),
        _payload("apparent_moment", "kg m"),
        # The reported-sigma coefficients (.reported_std), last.
        *[_filter(key, "see FilterTuning", "reported sigma (.reported_std)") for key in SIGMA_KEYS],
    )),
)  # fmt: skip
#: The filter's constant noise densities (vehicle file [filter]); the input-dependent ones
#: (default 0) are :data:`INPUT_DENSITY_FIELDS`.
NOISE_FIELDS = ("process_noise_density", "suspension_noise_density", "constraint_noise_density")
#: The input-dependent noise densities (models/measurement_noise.py).
INPUT_DENSITY_FIELDS = (
    "suspension_noise_rate_density",
    "suspension_noise_hub_density",
    "constraint_noise_acceleration_density",
)
#: Every density ``wheelload tune`` fits: the constant ones, then the input-dependent ones.
TUNED = TUNING.subset("tuned_densities", NOISE_FIELDS + INPUT_DENSITY_FIELDS)
#: The payload filter's part of the tuning vector.
PAYLOAD = TUNING.subset(
    "payload_tuning", [name for name in TUNING.field_names() if name.startswith("payload_")]
)
#: Scalar names of the constant densities, of every tuned density, of the payload's entries.
NOISE_DENSITIES = TUNING.subset("noise_densities", NOISE_FIELDS).names()
TUNED_DENSITIES = TUNED.names()
PAYLOAD_TUNING = PAYLOAD.names()
#: Position of each entry of the tuning vector (:meth:`Layout.index` of :data:`TUNING`).
TUNING_INDEX = {name: TUNING.index(name) for name in TUNING.names()}
#: The entries read from the vehicle file's ``[filter]`` under their own key.
_FILTER_KEYS = {name: key for name, key in TUNING.file_keys().items() if key[:-1] == ("filter",)}
#: Nominal sample interval [s] where no log gives one (100 Hz).
DEFAULT_SAMPLE_INTERVAL = 0.01
#: The guard settings' entries of the tuning vector (:meth:`GuardSettings.names` order).
GUARD_TUNING = TUNING.span(GuardSettings.names()[0], GuardSettings.names()[-1])
#: The payload filter's entries of the tuning vector (:data:`PAYLOAD_TUNING` order).
PAYLOAD_SLICE = TUNING.span(PAYLOAD.field_names()[0], PAYLOAD.field_names()[-1])
#: The reported-sigma coefficients (:mod:`.reported_std`): the last entries.
SIGMA_TUNING = TUNING.span(SIGMA_KEYS[0], SIGMA_KEYS[-1])


def payload_tuning(vehicle: Vehicle) -> np.ndarray:
    """The vehicle file's ``[filter.payload]`` in :data:`PAYLOAD_TUNING` order.

    Estimation is off where the file says travel is zeroed at the start of a log.
    """
    t = vehicle.filter.payload
    values = {field.name: getattr(t, field.file_key[-1]) for field in PAYLOAD.fields}
    values["payload_estimate"] = float(t.estimate and t.travel_from_reference)
    return PAYLOAD.pack(values)


def tuning_vector(
    vehicle: Vehicle,
    sample_interval: float = DEFAULT_SAMPLE_INTERVAL,
    settings: GuardSettings | None = None,
) -> np.ndarray:
    r"""The filter tuning in :data:`TUNING` order: the vehicle file's, interval, guards.

    ``sample_interval`` is the log's nominal interval [s]: the measurement
    noise is :math:`R = r / \Delta t_{nominal}` whatever the gap before a
    sample. ``settings``: default the vehicle's
    (:func:`~wheelload.estimators.guards.settings.guard_settings_for`).
    """
    settings = guard_settings_for(vehicle) if settings is None else settings
    tuning = vehicle.filter
    if not 0.0 < sample_interval < MAX_INTERVAL:
        raise ValueError(f"sample interval must be > 0 s and finite, got {sample_interval}")
    vector = TUNING.pack(
        {
            **{name: getattr(tuning, key[-1]) for name, key in _FILTER_KEYS.items()},
            "sample_interval": sample_interval,
            **dict(zip(GuardSettings.names(), settings.vector(), strict=True)),
            **PAYLOAD.unpack(payload_tuning(vehicle)),
        }
    )
    # The vehicle file's [filter] gate_scale (written by ``wheelload tune``) on the gate's S.
    vector[TUNING.index("innovation_variance_scale")] *= tuning.gate_scale
    return vector


def with_filter_sigma(tuning: np.ndarray) -> np.ndarray:
    """``tuning`` with the reported sigma the filter's own, sqrt(P_ii) (:mod:`.reported_std`:
    ``sigma_covariance`` 1, every other term 0); the loads do not change."""
    tuning = np.array(tuning, float)
    tuning[SIGMA_TUNING] = [1.0 if key == "sigma_covariance" else 0.0 for key in SIGMA_KEYS]
    return tuning


def noise_densities(vehicle: Vehicle) -> np.ndarray:
    """The vehicle file's noise densities in :data:`TUNED_DENSITIES` order (constant, then
    input-dependent)."""
    return TUNING.values(tuning_vector(vehicle), TUNED_DENSITIES)


def nominal_interval(t: np.ndarray) -> float:
    """Median of the positive finite sample intervals of a log (default if none), a block
    of time stamps at a time (a long log's may be on disk)."""
    t = np.asarray(t, float)
    passes = step_blocks(t)

    def kept():
        for _, dt in passes():
            yield dt[np.isfinite(dt) & (dt > 0) & (dt < MAX_INTERVAL)]

    count = sum(dt.size for dt in kept())
    return float(order_statistics.blocked_median(kept, count)) if count else DEFAULT_SAMPLE_INTERVAL
