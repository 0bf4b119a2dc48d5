r"""The optional ``[sensors]`` section of a vehicle file: the logged sensors' noise.

What the estimators derive from the log's own signals and so must know of the sensor that
logged them, as its data sheet states it. Today: the gyroscope's rate noise density
:math:`N`, which sets the body-rate derivative filter's measurement noise
:math:`r = N^2 / (2\,\Delta t)` (white to the Nyquist frequency;
:class:`~wheelload.estimators.logs.signals.RateDerivativeFilter`). A file without the
section takes an MTi-1 class IMU's figure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from wheelload.models.vehicle.section_checks import require_positive

#: rad/s/sqrt(Hz): Xsens MTi-1 series, 0.007 deg/s/sqrt(Hz) (studies/drive/sensors.py).
MTI_1_GYRO_NOISE_DENSITY = 0.007 * math.pi / 180.0


@dataclass(frozen=True, kw_only=True)
class Sensors:
    """``[sensors]``: the gyroscope's rate noise density [rad/s/sqrt(Hz)] (data sheet
    figures are in deg/s/sqrt(Hz): multiply by pi/180)."""

    gyro_noise_density: float = MTI_1_GYRO_NOISE_DENSITY

    def _check(self) -> None:
        require_positive(self, "gyro_noise_density")
