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

import numpy as np

from wheelload.estimators.guards.settings import GuardSettings, guard_settings_for
from wheelload.estimators.kernels import order_statistics
from wheelload.estimators.types import step_blocks
from wheelload.models import Vehicle
from wheelload.models.input_validity import MAX_INTERVAL
from wheelload.models.measurement_noise import INPUT_DENSITIES
from wheelload.models.vehicle.description import SIGMA_KEYS

#: The payload filter's entries of the tuning vector, in order.
PAYLOAD_TUNING = (
    "payload_estimate",
    "payload_mass_std",
    "payload_position_std_x",
    "payload_position_std_y",
    "payload_position_std_z",
    "payload_residual_density_vertical",
    "payload_residual_density_pitch",
    "payload_residual_density_roll",
    "payload_drift_density",
    "payload_standstill_density",
    "payload_standstill_speed",
    "payload_gate",
    "payload_acceleration_scale_vertical",
    "payload_acceleration_scale_pitch",
    "payload_acceleration_scale_roll",
    "payload_apparent_mass",
    "payload_apparent_moment",
)


def payload_tuning(vehicle: Vehicle) -> np.ndarray:
    """The vehicle file's ``[filter.payload]`` in :data:`PAYLOAD_TUNING` order.

    Estimation is off where the file says travel is zeroed at the start of a log.
    """
    t = vehicle.filter.payload
    on = t.estimate and t.travel_from_reference
    return np.array(
        [
            float(on),
            t.mass_std,
            *t.position_std,
            *t.residual_density,
            t.drift_density,
            t.standstill_density,
            t.standstill_speed,
            t.gate,
            *t.acceleration_scale,
            t.apparent_mass,
            t.apparent_moment,
        ]  # fmt: skip
    )


#: Order of the tuning vector.
TUNING = (
    "process_noise_density",
    "suspension_noise_density",
    "constraint_noise_vertical",
    "constraint_noise_pitch",
    "constraint_noise_roll",
    "sample_interval",
    *GuardSettings.names(),
    *INPUT_DENSITIES,
    *PAYLOAD_TUNING,
    *SIGMA_KEYS,
)
#: The filter's constant noise densities: the first entries of the tuning vector (vehicle
#: file [filter]); the input-dependent ones (default 0) are :data:`INPUT_DENSITIES`, last.
NOISE_DENSITIES = TUNING[:5]
#: Every density ``wheelload tune`` fits: the constant ones, then the input-dependent ones.
TUNED_DENSITIES = NOISE_DENSITIES + INPUT_DENSITIES
#: Position of each entry of the tuning vector.
TUNING_INDEX = {name: k for k, name in enumerate(TUNING)}
#: Nominal sample interval [s] where no log gives one (100 Hz).
DEFAULT_SAMPLE_INTERVAL = 0.01
#: The guard settings' entries of the tuning vector (:meth:`GuardSettings.names` order).
_GUARD_START = TUNING_INDEX["sample_interval"] + 1
GUARD_TUNING = slice(_GUARD_START, _GUARD_START + len(GuardSettings.names()))
_VARIANCE_SCALE = TUNING_INDEX["innovation_variance_scale"]
#: The payload filter's entries of the tuning vector (:data:`PAYLOAD_TUNING` order).
PAYLOAD_SLICE = slice(TUNING_INDEX[PAYLOAD_TUNING[0]], TUNING_INDEX[PAYLOAD_TUNING[-1]] + 1)
#: The reported-sigma coefficients (:mod:`.reported_std`): the last entries.
SIGMA_TUNING = slice(TUNING_INDEX[SIGMA_KEYS[0]], TUNING_INDEX[SIGMA_KEYS[-1]] + 1)


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
    vector = np.array(
        [
            tuning.process_noise_density,
            tuning.suspension_noise_density,
            *tuning.constraint_noise_density,
            sample_interval,
            *settings.vector(),
            *tuning.input_densities(),
            *payload_tuning(vehicle),
            *tuning.sigma_model(),
        ]
    )
    # The vehicle file's [filter] gate_scale (written by ``wheelload tune``) on the gate's S.
    vector[_VARIANCE_SCALE] *= tuning.gate_scale
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
    return tuning_vector(vehicle)[[TUNING_INDEX[name] for name in TUNED_DENSITIES]]


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
