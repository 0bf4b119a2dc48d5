"""Estimator output: loads, standard deviations, constraint residuals and status bits.

The per-sample :class:`StepFlag` bits are written in the column ``status``
(files written before it was renamed have ``flags``; :func:`read_estimates`
reads both).
"""

from __future__ import annotations

import dataclasses
import enum
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from wheelload.models.conventions import WHEELS
from wheelload.models.loaded_vehicle import MASS_PROPERTIES

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

RESIDUALS = ("residual_vertical", "residual_pitch", "residual_roll")
#: Columns of the online mass properties: the values, then their std.
MASS_PROPERTY_COLUMNS = (*MASS_PROPERTIES, *(f"{name}_std" for name in MASS_PROPERTIES))


class StepFlag(enum.IntFlag):
    """Per-sample status bits: which updates were skipped, and why.

    ``AZ_ASSUMED_G``: the log has no ``az``; :math:`a_z = g` was assumed.
    ``AERO_OFF_NO_SPEED``: no ``vx`` and no wheel speeds; aerodynamic terms off.
    ``SPEED_FROM_WHEELS``: ``vx`` is the mean of the logged wheel speeds.

    ``STEP_REJECTED``: the sample interval is not a positive finite number
    (``TwoStageKF.step`` and the generated C), or, in C only, the step's
    result would not be finite; the state is then held and every update flag
    is set too.
    """

    SUSPENSION_FL_SKIPPED = 1
    SUSPENSION_FR_SKIPPED = 2
    SUSPENSION_RL_SKIPPED = 4
    SUSPENSION_RR_SKIPPED = 8
    VERTICAL_SKIPPED = 16
    PITCH_SKIPPED = 32
    ROLL_SKIPPED = 64
    STEP_REJECTED = 128
    # Guards (estimators/guards/settings.py), bits 8-15, in the
    # order of the step's ``status`` output.
    INNOVATION_GATED = 1 << 8  # an update row skipped: y^2 > gate * S
    GATE_RELEASED = 1 << 9  # a row taken after gate_release_time of rejections
    TRAVEL_IMPLAUSIBLE = 1 << 10  # a travel or travel rate out of range: treated as missing
    ACCELERATION_IMPLAUSIBLE = 1 << 11  # |a| above max_acceleration: treated as missing
    SPEED_IMPLAUSIBLE = 1 << 12  # |vx| above max_speed: treated as missing
    TRAVEL_FAULT = 1 << 13  # a travel channel isolated as faulty: dropped
    IMU_FAULT = 1 << 14  # an accelerometer axis isolated as faulty: dropped
    COVARIANCE_LIMITED = 1 << 15  # the covariance floor or ceiling acted
    # Bits 16-19: a model term (wheelload.models.terms) switched on in the
    # vehicle file was dropped for this sample because an input it needs is
    # missing, or ran on that input's held last valid value (with INPUT_HELD); the
    # updates themselves went ahead.
    BODY_INERTIA_DROPPED = 1 << 16  # no wx_dot, wy_dot (no body rates in the log)
    UNSPRUNG_INERTIA_DROPPED = 1 << 17  # a hub accelerometer az_* missing
    # road frame or link loads dropped (an IMU axis or vx missing), or the road frame's
    # attitude from the equilibrium instead of the travels (a travel missing)
    ROAD_FRAME_OR_LINKS_DROPPED = 1 << 18
    IMU_TERMS_DROPPED = 1 << 19  # lever arm (no rates) or mounting (an IMU axis missing)
    # Bits 20-23: inputs the log did not have (estimators/logs/signals.py).
    AZ_ASSUMED_G = 1 << 20
    AERO_OFF_NO_SPEED = 1 << 21
    SPEED_FROM_WHEELS = 1 << 22
    # Bits 24-27: guards (estimators/guards/settings.py), after the eight of bits 8-15
    # in ``status``.
    TRAVEL_JUMP = 1 << 24  # a travel jumped faster than max_travel_rate and froze: dropped
    # a body rate or its derivative out of range, a rate jump beyond max_angular_acceleration,
    # or a derivative within rate_settle_time of one: treated as missing
    RATE_IMPLAUSIBLE = 1 << 25
    INPUT_HELD = 1 << 26  # a missing or gated input's last valid value fed the model terms
    LOAD_LIMITED = 1 << 27  # an update would leave +-load_limit m g: the sample is a prediction
    # Bit 28: the tyre step (estimators/family/tyres): a wheel's slip velocity changed faster
    # than R times the paper's w_th (high slip, corner-based paper Sec. IV); with
    # TyreSettings.switch_covariances the lateral filter took the paper's high-slip Q, R.
    HIGH_SLIP = 1 << 28
    # Bits 29-30: the step's interval against the nominal one (tuning sample_interval; guard
    # setting interval_band, estimators/guards/settings.py), the last of ``status``.
    INTERVAL_SHORT = 1 << 29  # dt < sample_interval / interval_band: refused, state held
    INTERVAL_LONG = 1 << 30  # dt > sample_interval * interval_band: a gap, or a slower log
    # Bit 31: a time-stamped measurement older than the rewind allows (estimators/kf/rewind.py):
    # dropped, the state unchanged.
    MEASUREMENT_TOO_OLD = 1 << 31

    @classmethod
    def update_flags(cls) -> tuple[StepFlag, ...]:
        """The flags in the order of the filter's ``used`` output.

        Seven updates (suspension FL..RR, vertical, pitch, roll), then the four
        droppable terms in ``wheelload.models.DROPPABLE`` order.
        """
        return (*tuple(cls)[:7], *_TERM_FLAGS)

    @classmethod
    def doubtful_mask(cls) -> int:
        """Bits of a sample whose inputs a guard doubted (implausible, gated, jumped, held,
        load-limited, a fault isolated): no sample to judge the vehicle file by."""
        return int(
            cls.INNOVATION_GATED | cls.TRAVEL_IMPLAUSIBLE | cls.ACCELERATION_IMPLAUSIBLE
            | cls.SPEED_IMPLAUSIBLE | cls.TRAVEL_FAULT | cls.IMU_FAULT | cls.TRAVEL_JUMP
            | cls.RATE_IMPLAUSIBLE | cls.INPUT_HELD | cls.LOAD_LIMITED
        )  # fmt: skip

    @classmethod
    def skipped_mask(cls) -> int:
        """Bits of a sample whose update was skipped or whose step was rejected.

        The seven update bits and STEP_REJECTED; a dropped model term (bits
        16-19) or an assumed input (bits 20-22) is not a skipped update.
        """
        return int(sum(tuple(cls)[:7])) | int(cls.STEP_REJECTED)

    @classmethod
    def assumed_mask(cls) -> int:
        """Bits of a sample whose input was assumed or derived (the log did not have it)."""
        return int(cls.AZ_ASSUMED_G | cls.AERO_OFF_NO_SPEED | cls.SPEED_FROM_WHEELS)

    @classmethod
    def guard_flags(cls) -> tuple[StepFlag, ...]:
        """The guard flags in the order of the filter's ``status`` output (bits 8-15, 24-27,
        29-30)."""
        return tuple(
            flag
            for flag in cls
            if 1 << 8 <= flag.value < 1 << 16
            or 1 << 24 <= flag.value < 1 << 28
            or 1 << 29 <= flag.value < 1 << 31
        )


_TERM_FLAGS = (
    StepFlag.BODY_INERTIA_DROPPED,
    StepFlag.UNSPRUNG_INERTIA_DROPPED,
    StepFlag.ROAD_FRAME_OR_LINKS_DROPPED,
    StepFlag.IMU_TERMS_DROPPED,
)


FAULT_COLUMNS = ("channel", "start", "end", "statistic")


@dataclass(frozen=True, kw_only=True)
class SensorFault:
    """An isolated sensor fault: channel, first and last flagged time [s], peak statistic."""

    channel: str
    start: float
    end: float
    statistic: float


@dataclass(frozen=True, kw_only=True)
class ModelError:
    """A vehicle-file parameter the log's residuals point at, and its likely value."""

    name: str  # e.g. "anti-roll bars", "travel zero d_fl"
    keys: tuple[str, ...]  # the file keys (or the channel, for a travel zero)
    unit: str
    file_value: tuple[float, ...]
    fitted_value: tuple[float, ...]
    explained: float  # share of the residual's variation it explains (0-1)
    runner_up: str = ""  # a hypothesis that explains almost as much, if any

    def message(self) -> str:
        """One line for the user: what fits, what the file says, where to change it."""
        if self.name.startswith("travel zero"):
            channel = self.keys[0]
            offset = self.fitted_value[0] * 1e3
            side = "high" if offset > 0 else "low"
            return (
                f"model error: {channel} reads {abs(offset):.1f} mm {side} at rest (its zero; "
                f"the travel warp of the quiet samples), taken off for the estimate; re-zero "
                f"the sensor or fix the channel map's offset"
            )
        fitted = ", ".join(_number(x) for x in self.fitted_value)
        given = ", ".join(_number(x) for x in self.file_value)
        also = f"; the {self.runner_up} fit almost as well" if self.runner_up else ""
        if self.name.endswith("motion ratio"):
            # Rates at the wheel are the damper's times the motion ratio squared.
            ratio = self.fitted_value[0] / self.file_value[0]
            return (
                f"model error: the {self.name.split()[0]} axle's spring, damper and bar "
                f"rates fit {ratio:.2f} times the file's ({', '.join(self.keys)}: spring "
                f"{fitted} {self.unit}, not {given}; it explains {100 * self.explained:.0f} % "
                f"of the equilibrium residual{also}), as if given at the damper with a motion "
                f"ratio of {min(ratio, 1 / ratio) ** 0.5:.2f} left out; give them at the wheel "
                f"(the damper's times the ratio squared): check the vehicle file, not the "
                f"sensors"
            )
        return (
            f"model error: the log's load transfer fits {self.name} of {fitted} {self.unit}, "
            f"not the file's {given} ({', '.join(self.keys)}: it explains "
            f"{100 * self.explained:.0f} % of the equilibrium residual{also}); "
            f"check the vehicle file, not the sensors"
        )


def _number(x: float) -> str:
    return f"{x:,.0f}".replace(",", " ") if abs(x) >= 100 else f"{x:.3g}"


@dataclass(frozen=True, kw_only=True, eq=False)
class Estimate:
    """Wheel-load estimates of ``n`` samples, wheel order FL, FR, RL, RR.

    ``residual`` is :math:`b - A x` after the update [N, N m, N m].

    ``has_std`` is False for a method that has no standard deviation (an
    algebraic or deterministic estimator): its ``std`` is then all zeros (never
    NaN) and :meth:`to_pandas` leaves the ``fz_std_*`` columns out.

    ``method``: the registered name of the method that made it (``""`` when not told:
    :meth:`named` sets it). :meth:`plot` draws it; its repr is one line, no arrays.
    """

    t: np.ndarray  # (n,)
    loads: np.ndarray  # (n, 4) N
    std: np.ndarray  # (n, 4) N
    residual: np.ndarray  # (n, 3)
    flags: np.ndarray  # (n,) StepFlag bits
    has_std: bool = True
    sensor_faults: tuple[SensorFault, ...] = ()  # isolated sensor faults, in time order
    # Vehicle-file parameters or travel zeros the log's residuals point at
    # (estimators/logs/model_error.py), at most one a log.
    model_errors: tuple[ModelError, ...] = ()
    # The loaded car's mass [kg], CG ahead of and left of the file's CG and CG height [m]
    # (MASS_PROPERTIES order), estimated online, and their std; None for a method without.
    mass_properties: np.ndarray | None = None  # (n, 4)
    mass_properties_std: np.ndarray | None = None  # (n, 4)
    method: str = ""  # the registered method's name, e.g. "kf" ("" when not told)
    # Where std comes from when it is not the method's own reported sigma (figure captions).
    std_source: str = ""
    # Tyre forces [N] in each tyre's frame (ISO 8855: x along the wheel heading in the road
    # plane, y to its left) and their std, (n, 4); None for a method without them.
    fx: np.ndarray | None = None
    fy: np.ndarray | None = None
    fx_std: np.ndarray | None = None
    fy_std: np.ndarray | None = None

    def named(self, method: str) -> Estimate:
        """This estimate labelled with the registered ``method`` name (arrays shared)."""
        return dataclasses.replace(self, method=method)

    def __repr__(self) -> str:
        """``Estimate(method='kf', samples=1353, t=0.01..13.53 s, ...)``: no arrays."""
        parts = [f"method={self.method!r}"] if self.method else []
        parts.append(f"samples={len(self)}")
        if len(self):
            parts.append(f"t={self.t[0]:.2f}..{self.t[-1]:.2f} s")
        parts.append(f"wheels={' '.join(WHEELS)}")
        source = self.std_source.split(" (")[0] if self.std_source else "reported"
        parts.append(f"std: {source}" if self.has_std else "std: none")
        skipped = int(np.count_nonzero(np.asarray(self.flags).astype(np.int64)
                                       & StepFlag.skipped_mask()))  # fmt: skip
        parts.append(f"flags: {skipped} skipped")
        if self.sensor_faults:
            parts.append(f"faults: {len(self.sensor_faults)}")
        return f"{type(self).__name__}({', '.join(parts)})"

    def plot(
        self, reference: np.ndarray | None = None, *, errors: bool = False, title: str = ""
    ) -> Figure:
        """Four panels (FL, FR, RL, RR): the loads, their ±2σ band and ``reference`` on top.

        ``reference``: the reference loads (n, 4) [N] of the same samples, e.g.
        ``signals.reference``; each panel then gives the RMS error and the coverage
        (share of samples with ``|error| < 2σ``). ``errors``: a panel under each wheel with
        the error and the ±2σ band around zero (the constraint residuals without a
        reference). Samples with a skipped update are marked. See
        :mod:`wheelload.estimators.estimate_figure`.

        Example
        -------
        >>> estimate.plot(signals.reference).savefig("loads.png")
        """
        from wheelload.estimators.estimate_figure import estimate_figure

        skipped = (np.asarray(self.flags).astype(np.int64) & StepFlag.skipped_mask()) != 0
        return estimate_figure(
            self.t, self.loads, self.std, has_std=self.has_std, skipped=skipped,
            reference=reference, residual=self.residual, errors=errors,
            title=title or self.method, std_source=self.std_source,
        )  # fmt: skip

    @property
    def faults(self) -> pd.DataFrame:
        """The ``faults`` table: ``channel, start, end, statistic``, one row per fault."""
        import pandas as pd

        return pd.DataFrame(
            {
                "channel": pd.Series([f.channel for f in self.sensor_faults], dtype=object),
                "start": pd.Series([f.start for f in self.sensor_faults], dtype=float),
                "end": pd.Series([f.end for f in self.sensor_faults], dtype=float),
                "statistic": pd.Series([f.statistic for f in self.sensor_faults], dtype=float),
            },
            columns=list(FAULT_COLUMNS),
        )

    def __len__(self) -> int:
        return len(self.t)

    def to_pandas(self) -> pd.DataFrame:
        """Columns ``t, fz_fl.., fz_std_fl.. (if has_std), residual_*.., mass.., mass_std..
        (if estimated: :data:`MASS_PROPERTY_COLUMNS`), fx_*, fx_std_*, fy_*, fy_std_* (if
        estimated), status`` (uint32 bits)."""
        import pandas as pd

        columns = {"t": self.t}
        columns.update({f"fz_{w}": self.loads[:, i] for i, w in enumerate(WHEELS)})
        if self.has_std:
            columns.update({f"fz_std_{w}": self.std[:, i] for i, w in enumerate(WHEELS)})
        columns.update({name: self.residual[:, i] for i, name in enumerate(RESIDUALS)})
        if self.mass_properties is not None:
            values = np.hstack([self.mass_properties, self.mass_properties_std])
            columns.update({name: values[:, i] for i, name in enumerate(MASS_PROPERTY_COLUMNS)})
        for prefix, values in (
            ("fx", self.fx),
            ("fx_std", self.fx_std),
            ("fy", self.fy),
            ("fy_std", self.fy_std),
        ):
            if values is not None:
                columns.update({f"{prefix}_{w}": values[:, i] for i, w in enumerate(WHEELS)})
        columns[STATUS] = self.flags.astype(np.uint32)  # bits 0-30 (StepFlag)
        return pd.DataFrame(columns)


STATUS = "status"
OLD_STATUS = "flags"  # the column's name before it collided with ``DataFrame.flags``


def read_estimates(path: str | Path) -> pd.DataFrame:
    """Read an estimates CSV or Parquet file; an old ``flags`` column is renamed ``status``."""
    import pandas as pd

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such estimates file")
    frame = (
        pd.read_parquet(path) if path.suffix.lower() in (".parquet", ".pq") else pd.read_csv(path)
    )
    if OLD_STATUS in frame.columns and STATUS not in frame.columns:
        frame = frame.rename(columns={OLD_STATUS: STATUS})
    if STATUS not in frame.columns:
        raise ValueError(f"{path}: no column '{STATUS}': not a wheelload estimates file")
    return frame
