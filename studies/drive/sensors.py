r"""Sensor models: a body IMU and four suspension displacement sensors.

A noise scale ``s`` multiplies every stochastic part (paper §IV-F); ``s = 0``
returns the clean signals.

IMU (MTi-1 class, Xsens MTi-1 series datasheet figures as quoted by
Kucharczyk et al., Transport and Aerospace Research 2023, table
"Characteristics of IMU Xsens MTi-1 sensors"): accelerometer noise density
120 µg/√Hz, bias instability 0.03 mg, bandwidth 324 Hz; gyroscope noise
density 0.007 °/s/√Hz, bias instability 10 °/h, bandwidth 255 Hz. Per sample

.. math:: y_k = x_k + b + \beta_k + N \sqrt{\min(B, f_s/2)}\, \epsilon_k, \quad
          \beta_{k+1} = \beta_k + \sigma_{rw} \sqrt{\Delta t}\, \eta_k

with a constant turn-on bias ``b`` (not in the quoted table: 5 mg and
0.2 °/s, 1 sigma, assumed for a MEMS part after factory calibration) and a
bias random walk whose 100 s growth equals the bias instability.

Suspension sensors (ILPS-19 class, 19 mm inductive linear sensor; the
ILPS-19 datasheet is not available to the project, so the figures are those
of a comparable 19 mm non-contact sensor, Positek P118: linearity ±0.25 % of
full scale), 150 mm stroke: linearity error ±0.25 % FS as a fixed smooth
curve per sensor, repeatability 0.02 mm (1 sigma, assumed), 12-bit logger
quantisation of the stroke (0.037 mm). The logged rate ``v`` is the true
rate plus the backward difference of the displacement error, so ``v`` stays
consistent with the noisy ``d``.

Hub accelerometers (``az_fl .. az_rr``, the wheel accelerometers of
semi-active damping systems; no datasheet is available to the project, so
the figures are assumed for a ±50 g MEMS part): noise density 1 mg/√Hz,
bandwidth 1 kHz, bias instability 1 mg, and a residual turn-on bias of 5 mg
(1 sigma) after the zeroing at standstill such systems do (the IMU's
assumption too); the same channel model as the IMU's. Written only when the
truth has them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from wheelload.models.conventions import GRAVITY, WHEELS

MICRO_G = 1e-6 * GRAVITY
DEG = np.pi / 180.0


@dataclass(frozen=True, kw_only=True)
class InertialNoise:
    """One inertial channel's errors: white noise to its bandwidth, a turn-on bias and a
    bias random walk that reaches ``bias_instability`` after ``instability_time``."""

    noise_density: float  # unit/sqrt(Hz)
    bandwidth: float  # Hz
    bias: float  # 1 sigma turn-on bias
    bias_instability: float
    instability_time: float = 100.0  # s


@dataclass(frozen=True, kw_only=True)
class ImuModel:
    accel_noise_density: float = 120.0 * MICRO_G  # m/s^2/sqrt(Hz)
    accel_bandwidth: float = 324.0  # Hz
    accel_bias: float = 5000.0 * MICRO_G  # m/s^2, 1 sigma turn-on bias (assumed)
    accel_bias_instability: float = 30.0 * MICRO_G  # m/s^2
    gyro_noise_density: float = 0.007 * DEG  # rad/s/sqrt(Hz)
    gyro_bandwidth: float = 255.0  # Hz
    gyro_bias: float = 0.2 * DEG  # rad/s, 1 sigma turn-on bias (assumed)
    gyro_bias_instability: float = 10.0 * DEG / 3600.0  # rad/s
    instability_time: float = 100.0  # s, horizon over which the walk reaches the instability

    @property
    def accelerometer(self) -> InertialNoise:
        """The errors of each accelerometer axis."""
        return InertialNoise(
            noise_density=self.accel_noise_density,
            bandwidth=self.accel_bandwidth,
            bias=self.accel_bias,
            bias_instability=self.accel_bias_instability,
            instability_time=self.instability_time,
        )

    @property
    def gyroscope(self) -> InertialNoise:
        """The errors of each gyroscope axis."""
        return InertialNoise(
            noise_density=self.gyro_noise_density,
            bandwidth=self.gyro_bandwidth,
            bias=self.gyro_bias,
            bias_instability=self.gyro_bias_instability,
            instability_time=self.instability_time,
        )


@dataclass(frozen=True, kw_only=True)
class HubAccelerometerModel(InertialNoise):
    noise_density: float = 1000.0 * MICRO_G  # m/s^2/sqrt(Hz)
    bandwidth: float = 1000.0  # Hz
    bias: float = 5000.0 * MICRO_G  # m/s^2, 1 sigma residual bias after zeroing
    bias_instability: float = 1000.0 * MICRO_G  # m/s^2
    instability_time: float = 100.0  # s


@dataclass(frozen=True, kw_only=True)
class TravelSensorModel:
    full_scale: float = 0.150  # m, stroke
    linearity: float = 0.0025  # fraction of full scale
    repeatability: float = 0.02e-3  # m, 1 sigma
    bits: int = 12


def _inertial_channel(clean, rng, dt, noise: InertialNoise, scale):
    count = clean.size
    white = noise.noise_density * np.sqrt(min(noise.bandwidth, 0.5 / dt))
    white = white * rng.standard_normal(count)
    step = noise.bias_instability / np.sqrt(noise.instability_time) * np.sqrt(dt)
    walk = np.cumsum(step * rng.standard_normal(count))
    return clean + scale * (noise.bias * rng.standard_normal() + walk + white)


def measure(
    truth: pd.DataFrame,
    scale: float,
    rng: np.random.Generator,
    imu: ImuModel = ImuModel(),
    travel: TravelSensorModel = TravelSensorModel(),
    hub: HubAccelerometerModel = HubAccelerometerModel(),
) -> pd.DataFrame:
    """Measured log columns from the clean ones in ``truth`` (``t vx ax.. wz d_* v_* az_* fz_*``).

    The hub channels ``az_*`` are measured when ``truth`` has them.
    """
    if scale < 0:
        raise ValueError(f"noise scale must be >= 0, got {scale}")
    dt = float(np.median(np.diff(truth["t"]))) if len(truth) > 1 else 0.01
    log = truth.copy()
    for axes, noise in (
        (("ax", "ay", "az"), imu.accelerometer),
        (("wx", "wy", "wz"), imu.gyroscope),
    ):
        for axis in axes:
            log[axis] = _inertial_channel(truth[axis].to_numpy(), rng, dt, noise, scale)
    step = scale * travel.full_scale / 2**travel.bits
    for wheel in WHEELS:
        d = truth[f"d_{wheel}"].to_numpy()
        phase = rng.uniform(0.0, 2.0 * np.pi)
        linear = (
            travel.linearity
            * travel.full_scale
            * np.sin(2.0 * np.pi * d / travel.full_scale + phase)
        )
        noisy = d + scale * (linear + travel.repeatability * rng.standard_normal(d.size))
        if step > 0:
            noisy = step * np.round(noisy / step)
        error = noisy - d
        log[f"d_{wheel}"] = noisy
        log[f"v_{wheel}"] = truth[f"v_{wheel}"].to_numpy() + np.diff(error, prepend=error[0]) / dt
    for wheel in WHEELS:
        if f"az_{wheel}" not in truth.columns:
            continue
        log[f"az_{wheel}"] = _inertial_channel(truth[f"az_{wheel}"].to_numpy(), rng, dt, hub, scale)
    return log
