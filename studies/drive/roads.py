"""Roads for the scenarios: a centre line with elevation, grade, bank and roughness.

A :class:`Road` couples the plant's :class:`~wheelload.models.plant.road_surface.RoadSurface`
with the planar centre line (for plots and the driver's preview), the driver's
target lateral offset ``target`` (a lane change is a target offset on a
straight road) and the usable half-widths.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wheelload.models.plant.road_surface import RoadSurface
from wheelload.models.vehicle.plant_section import Roughness


@dataclass(frozen=True, kw_only=True)
class Road:
    """A road on a uniform arc-length grid; ``length`` is the lap length of a closed track."""

    surface: RoadSurface
    x: np.ndarray  # m, centre line in the plane
    y: np.ndarray  # m
    heading: np.ndarray  # rad
    target: np.ndarray  # m, driver's target lateral offset (left > 0)
    half_width: np.ndarray  # m, usable half-width of the road around the centre line
    length: float  # m, lap length (closed) or road length (open)

    @property
    def s(self) -> np.ndarray:
        return self.surface.s


def integrate_centre_line(s: np.ndarray, curvature: np.ndarray, heading0: float = 0.0):
    """Planar centre line from curvature.

    .. math:: \\psi' = \\kappa, \\quad (x', y') = (\\cos\\psi, \\sin\\psi)
    """
    ds = np.diff(s)
    heading = heading0 + np.concatenate(
        [[0.0], np.cumsum(0.5 * (curvature[1:] + curvature[:-1]) * ds)]
    )
    mid = 0.5 * (heading[1:] + heading[:-1])
    x = np.concatenate([[0.0], np.cumsum(np.cos(mid) * ds)])
    y = np.concatenate([[0.0], np.cumsum(np.sin(mid) * ds)])
    return x, y, heading


def build_road(
    s: np.ndarray,
    *,
    curvature: np.ndarray | None = None,
    elevation: np.ndarray | None = None,
    bank: np.ndarray | None = None,
    target: np.ndarray | None = None,
    half_width: float | np.ndarray = 5.0,
    roughness: tuple[np.ndarray, np.ndarray] | None = None,
    centre_line: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    length: float | None = None,
) -> Road:
    """A road from its columns on grid ``s``; missing columns are zero (flat, straight)."""
    s = np.asarray(s, float)
    zero = np.zeros_like(s)
    curvature = zero if curvature is None else np.asarray(curvature, float)
    elevation = zero if elevation is None else np.asarray(elevation, float)
    left, right = (zero, zero) if roughness is None else roughness
    x, y, heading = integrate_centre_line(s, curvature) if centre_line is None else centre_line
    surface = RoadSurface(
        s=s,
        elevation=elevation,
        grade=np.gradient(elevation, s),
        bank=zero if bank is None else np.asarray(bank, float),
        curvature=curvature,
        roughness_left=left,
        roughness_right=right,
    )
    return Road(
        surface=surface,
        x=x,
        y=y,
        heading=heading,
        target=zero if target is None else np.asarray(target, float),
        half_width=np.broadcast_to(np.asarray(half_width, float), s.shape).copy(),
        length=float(s[-1] - s[0]) if length is None else float(length),
    )


def smooth_step(s: np.ndarray, start: float, length: float) -> np.ndarray:
    """Cosine ramp from 0 (s <= start) to 1 (s >= start + length)."""
    phase = np.clip((np.asarray(s) - start) / length, 0.0, 1.0)
    return 0.5 * (1.0 - np.cos(np.pi * phase))


ISO_CLASSES = ("A", "B", "C", "D")


def iso8608_profile(
    s: np.ndarray, road_class: str, model: Roughness, rng: np.random.Generator
) -> np.ndarray:
    r"""One random road profile of an ISO 8608 class on the uniform grid ``s`` [m].

    Sum of harmonics with random phases, amplitudes
    :math:`\sqrt{2 G_d(n_k) \Delta n}` over the model's band, then averaged
    over the tyre's enveloping length (a moving mean).
    """
    if road_class not in ISO_CLASSES:
        raise ValueError(f"roughness class must be one of {ISO_CLASSES}, got '{road_class}'")
    psd0 = model.class_psd[ISO_CLASSES.index(road_class)]
    ds = float(s[1] - s[0])
    count = int(2 ** np.ceil(np.log2(max(len(s), 2))))
    freqs = np.fft.rfftfreq(count, ds)
    band = (freqs >= model.band[0]) & (freqs <= model.band[1])
    psd = np.zeros_like(freqs)
    psd[band] = psd0 * (freqs[band] / model.reference_frequency) ** (-model.waviness)
    dn = freqs[1] - freqs[0]
    amplitude = np.sqrt(2.0 * psd * dn)
    phases = rng.uniform(0.0, 2.0 * np.pi, freqs.size)
    spectrum = 0.5 * count * amplitude * np.exp(1j * phases)
    profile = np.fft.irfft(spectrum, count)[: len(s)]
    window = max(1, int(round(model.enveloping_length / ds)))
    return np.convolve(profile, np.ones(window) / window, mode="same")
