r"""Sensor models: a body IMU, four suspension displacement sensors and the speed.

A :class:`SensorGrade` bundles one of each (``GRADES``: ``clean``, ``mti-1``,
``consumer-mems``), selected by name (:func:`sensor_grade`); ``mti-1`` is the default.

A noise scale ``s`` multiplies the sensor errors (paper §IV-F) as a
:class:`NoiseScaling` says: every error (``ALL``; ``s = 0`` returns the clean
signals) or only what the paper scales (``PAPER_SENSORS``, ``PAPER_STOCHASTIC``).

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

Consumer-MEMS grade (``consumer-mems``): 2.5 times the MTi-1 grade's noise
densities, turn-on biases and bias instabilities: accelerometer 300 µg/√Hz and
12.5 mg, gyroscope 0.0175 °/s/√Hz and 0.5 °/s. These bracket two consumer IMUs'
data sheets: Bosch Sensortec BMI088 (BST-BMI088-DS001, Table 1: accelerometer
output noise density 175 µg/√Hz x/y, zero-g offset ±20 mg; gyroscope rate noise
density 0.014 °/s/√Hz, zero-rate offset ±1 °/s) and TDK InvenSense MPU-6050
(PS-MPU-6000A-00 rev. 3.4, §6.1-6.2: accelerometer power spectral density
400 µg/√Hz, zero-g tolerance ±50 mg x/y; gyroscope rate noise spectral density
0.005 °/s/√Hz, zero-rate tolerance ±20 °/s); the biases are the residuals after
the standstill zeroing the MTi-1 grade assumes, a quarter to a tenth of the raw
offsets. Bandwidths as the parts' digital low-pass filters at their highest
settings: 260 Hz accelerometer, 256 Hz gyroscope (MPU-6050 DLPF_CFG = 0). Travel:
the issue's MEMS case, 0.05 mm white noise (1 sigma) and a 0.1 mm logger step
beside the same linearity error; speed ``vx``: 0.05 m/s white noise (1 sigma).
The MTi-1 grade logs ``vx`` clean (a wheel-speed or GNSS speed far better than
the loads need), the consumer grade with that noise. Wheel spins ``omega_*`` (when the
truth has them): 0.02 rad/s white noise (1 sigma, every grade), drawn after every other
channel so that a log without them keeps its noise; the drive/brake torques ``torque_*``
and the steer angle are logged as the plant applies them (their errors are not modelled).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, fields

import numpy as np
import pandas as pd

from wheelload.models.conventions import GRAVITY, WHEELS

MICRO_G = 1e-6 * GRAVITY
DEG = np.pi / 180.0


class NoiseScaling(enum.Enum):
    """Which sensor errors the noise scale ``s`` multiplies (Siegloff & Choi §IV-F).

    The paper: "synthetic noise was injected into the measured accelerometer channels and
    suspension displacement signals [...] the same displacement-sensor error realization
    was also applied to the wheel-travel channels used by the anti-roll-bar term";
    "Accelerometer corruption was modeled as the combination of band-limited white noise,
    a constant bias, and a slowly varying bias random walk"; "Suspension displacement
    sensing was corrupted using a bounded error model including linearity, repeatability,
    and quantization effects"; "A scalar factor s [...] was applied uniformly to the
    stochastic components of both noise models, with s = 0 denoting the noise-free case."

    So s reaches the accelerometers and the travel sensors only (the one travel channel
    feeds both the spring and the bar term, as the paper's shared realization); the
    gyroscopes, hub accelerometers and speed, which the paper does not perturb, keep their
    nominal (s = 1) errors in both paper variants. Which of the two models' components are
    "the stochastic components" the text leaves open, hence two variants:

    ``PAPER_SENSORS``: every listed component of the two models, the accelerometers'
    white noise, turn-on bias and bias walk and the travel sensors' linearity error,
    repeatability and logger step. ``PAPER_STOCHASTIC``: the components random in time
    only, the accelerometers' white noise and bias walk and the travels' repeatability;
    the turn-on bias, the linearity curve and the logger step (fixed for a given sensor)
    stay nominal. ``ALL``: s multiplies every error of every sensor.
    """

    PAPER_SENSORS = "paper-sensors"
    PAPER_STOCHASTIC = "paper-stochastic"
    ALL = "all"

    def factors(self, scale: float) -> ErrorFactors:
        """The factor on each error component at noise scale ``scale``."""
        if self is NoiseScaling.ALL:
            return ErrorFactors(**dict.fromkeys(ErrorFactors.names(), scale))
        factors = dict.fromkeys(ErrorFactors.names(), 1.0)
        scaled = ["accel_random", "travel_random"]
        if self is NoiseScaling.PAPER_SENSORS:
            scaled += ["accel_bias", "travel_linearity", "travel_step"]
        factors.update(dict.fromkeys(scaled, scale))
        return ErrorFactors(**factors)


@dataclass(frozen=True, kw_only=True)
class ErrorFactors:
    """Multipliers of the sensor error components (:meth:`NoiseScaling.factors`)."""

    accel_random: float  # accelerometers' white noise and bias walk
    accel_bias: float  # accelerometers' turn-on bias
    gyro: float  # every gyroscope error
    travel_random: float  # travel repeatability (white)
    travel_linearity: float  # travel linearity curve
    travel_step: float  # travel logger step
    hub: float  # every hub-accelerometer error
    speed: float  # speed noise

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(field.name for field in fields(cls))


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
    """A travel sensor: a smooth linearity error, white noise and the logger's step."""

    full_scale: float = 0.150  # m, stroke
    linearity: float = 0.0025  # fraction of full scale
    repeatability: float = 0.02e-3  # m, 1 sigma white noise
    resolution: float = 0.150 / 2**12  # m, logger step (12 bits of the stroke); 0: none


@dataclass(frozen=True, kw_only=True)
class SpeedSensorModel:
    """The logged forward speed ``vx``: white noise."""

    noise: float = 0.0  # m/s, 1 sigma


@dataclass(frozen=True, kw_only=True)
class WheelSpeedSensorModel:
    """The logged wheel spins ``omega_*``: white noise."""

    noise: float = 0.02  # rad/s, 1 sigma


@dataclass(frozen=True, kw_only=True)
class SensorGrade:
    """A set of sensors: body IMU, travel sensors, speed and hub accelerometers."""

    name: str
    imu: ImuModel
    travel: TravelSensorModel
    speed: SpeedSensorModel
    hub: HubAccelerometerModel = HubAccelerometerModel()
    wheel_speed: WheelSpeedSensorModel = WheelSpeedSensorModel()


def _scaled_imu(factor: float) -> ImuModel:
    """The MTi-1 grade's IMU with every noise density, bias and instability times ``factor``
    and the consumer parts' bandwidths."""
    mti = ImuModel()
    return ImuModel(
        accel_noise_density=factor * mti.accel_noise_density,
        accel_bandwidth=260.0,
        accel_bias=factor * mti.accel_bias,
        accel_bias_instability=factor * mti.accel_bias_instability,
        gyro_noise_density=factor * mti.gyro_noise_density,
        gyro_bandwidth=256.0,
        gyro_bias=factor * mti.gyro_bias,
        gyro_bias_instability=factor * mti.gyro_bias_instability,
    )


MTI_1 = SensorGrade(
    name="mti-1", imu=ImuModel(), travel=TravelSensorModel(), speed=SpeedSensorModel()
)
CONSUMER_MEMS = SensorGrade(
    name="consumer-mems",
    imu=_scaled_imu(2.5),
    travel=TravelSensorModel(repeatability=0.05e-3, resolution=0.1e-3),
    speed=SpeedSensorModel(noise=0.05),
)
CLEAN = SensorGrade(
    name="clean",
    imu=_scaled_imu(0.0),
    travel=TravelSensorModel(linearity=0.0, repeatability=0.0, resolution=0.0),
    speed=SpeedSensorModel(),
    hub=HubAccelerometerModel(noise_density=0.0, bias=0.0, bias_instability=0.0),
)
#: Every grade by name.
GRADES: dict[str, SensorGrade] = {
    CLEAN.name: CLEAN,
    MTI_1.name: MTI_1,
    CONSUMER_MEMS.name: CONSUMER_MEMS,
}


def sensor_grade(name: str) -> SensorGrade:
    """The grade called ``name``, or an error naming the grades."""
    if name not in GRADES:
        raise ValueError(f"unknown sensor grade '{name}'; choose from {', '.join(GRADES)}")
    return GRADES[name]


def _inertial_channel(clean, rng, dt, noise: InertialNoise, random: float, bias: float):
    """``clean`` plus white noise and bias walk times ``random``, turn-on bias times ``bias``."""
    count = clean.size
    white = noise.noise_density * np.sqrt(min(noise.bandwidth, 0.5 / dt))
    white = white * rng.standard_normal(count)
    step = noise.bias_instability / np.sqrt(noise.instability_time) * np.sqrt(dt)
    walk = np.cumsum(step * rng.standard_normal(count))
    return clean + bias * noise.bias * rng.standard_normal() + random * (walk + white)


def measure(
    truth: pd.DataFrame,
    scale: float,
    rng: np.random.Generator,
    grade: SensorGrade = MTI_1,
    scaling: NoiseScaling = NoiseScaling.ALL,
) -> pd.DataFrame:
    """Measured log columns from the clean ones in ``truth`` (``t vx ax.. wz d_* v_* az_* fz_*``)
    with the sensors of ``grade`` at noise scale ``scale`` (``clean``: none) applied as
    ``scaling`` says (:class:`NoiseScaling`).

    The hub channels ``az_*`` are measured when ``truth`` has them. The random draws are
    the same, in the same order, for either scaling (common random numbers).
    """
    if scale < 0:
        raise ValueError(f"noise scale must be >= 0, got {scale}")
    imu, travel = grade.imu, grade.travel
    k = scaling.factors(scale)
    dt = float(np.median(np.diff(truth["t"]))) if len(truth) > 1 else 0.01
    log = truth.copy()
    for axes, noise, random, bias in (
        (("ax", "ay", "az"), imu.accelerometer, k.accel_random, k.accel_bias),
        (("wx", "wy", "wz"), imu.gyroscope, k.gyro, k.gyro),
    ):
        for axis in axes:
            clean = truth[axis].to_numpy()
            log[axis] = _inertial_channel(clean, rng, dt, noise, random, bias)
    step = k.travel_step * travel.resolution
    for wheel in WHEELS:
        d = truth[f"d_{wheel}"].to_numpy()
        phase = rng.uniform(0.0, 2.0 * np.pi)
        linear = (
            travel.linearity
            * travel.full_scale
            * np.sin(2.0 * np.pi * d / travel.full_scale + phase)
        )
        white = travel.repeatability * rng.standard_normal(d.size)
        noisy = d + k.travel_linearity * linear + k.travel_random * white
        if step > 0:
            noisy = step * np.round(noisy / step)
        error = noisy - d
        log[f"d_{wheel}"] = noisy
        log[f"v_{wheel}"] = truth[f"v_{wheel}"].to_numpy() + np.diff(error, prepend=error[0]) / dt
    for wheel in WHEELS:
        if f"az_{wheel}" not in truth.columns:
            continue
        hub = truth[f"az_{wheel}"].to_numpy()
        log[f"az_{wheel}"] = _inertial_channel(hub, rng, dt, grade.hub, k.hub, k.hub)
    if k.speed * grade.speed.noise > 0 and "vx" in truth.columns:
        vx = truth["vx"].to_numpy()
        log["vx"] = vx + k.speed * grade.speed.noise * rng.standard_normal(vx.size)
    for wheel in WHEELS:
        if k.speed * grade.wheel_speed.noise > 0 and f"omega_{wheel}" in truth.columns:
            spin = truth[f"omega_{wheel}"].to_numpy()
            log[f"omega_{wheel}"] = spin + k.speed * grade.wheel_speed.noise * rng.standard_normal(
                spin.size
            )
    return log
