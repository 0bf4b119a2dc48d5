"""The wiring and unit mistakes a log can carry, applied to a clean log frame.

Each corruption maps a frame with the log columns (``t vx ax ay az wx wy wz
d_* ...``) to a corrupted copy; :func:`wiring_margins` runs
:func:`wheelload.estimators.logs.checks.check_wiring` on clean and corrupted
logs and prints each check's statistic (the margins of the checks):

    python -m wheelload.studies.experiments.faults.log_corruptions LOG.csv [LOG.csv ...]
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators.logs.checks import Outcome, WiringReport, check_wiring
from wheelload.models.conventions import GRAVITY, WHEELS

TRAVEL = ("d_fl", "d_fr", "d_rl", "d_rr")
#: The bundled scenarios short enough to simulate in the test suite (a few
#: seconds each); hockenheim and nordschleife are run by the command above.
SHORT_SCENARIOS = (
    "iso-dlc", "brake-in-turn", "accel-in-turn", "bounce-sweep", "slope-20",
    "chicane-bank-30", "chicane-incline-20", "wheel-lift",
)  # fmt: skip


def _scaled(column: str, factor: float) -> Callable[[pd.DataFrame], pd.DataFrame]:
    return lambda frame: frame.assign(**{column: frame[column] * factor})


def _swapped(pairs: tuple[tuple[str, str], ...]) -> Callable[[pd.DataFrame], pd.DataFrame]:
    def corrupt(frame: pd.DataFrame) -> pd.DataFrame:
        mapping = {}
        for a, b in pairs:
            for prefix in ("d_", "v_"):
                mapping[prefix + a], mapping[prefix + b] = prefix + b, prefix + a
        return frame.rename(columns=mapping)[list(frame.columns)]

    return corrupt


def _travel_sign(wheels: tuple[str, ...]) -> Callable[[pd.DataFrame], pd.DataFrame]:
    columns = [f"{p}_{w}" for w in wheels for p in ("d", "v")]
    return lambda frame: frame.assign(**{c: -frame[c] for c in columns})


def _without_rates(frame: pd.DataFrame) -> pd.DataFrame:
    return frame.drop(columns=[c for c in ("wx", "wy", "wz") if c in frame.columns])


CORRUPTIONS: dict[str, Callable[[pd.DataFrame], pd.DataFrame]] = {
    "vx in km/h": _scaled("vx", 3.6),
    "vx in mph": _scaled("vx", 2.23694),
    "ay in g": _scaled("ay", 1.0 / GRAVITY),
    "ax in g": _scaled("ax", 1.0 / GRAVITY),
    "ay sign": _scaled("ay", -1.0),
    "ax sign": _scaled("ax", -1.0),
    "wz in deg/s": _scaled("wz", 180.0 / np.pi),
    "travel sign": _travel_sign(WHEELS),
    "d_fl sign": _travel_sign(("fl",)),
    "d_rr sign": _travel_sign(("rr",)),
    "left/right swapped": _swapped((("fl", "fr"), ("rl", "rr"))),
    "front left/right swapped": _swapped((("fl", "fr"),)),
    "front/rear swapped": _swapped((("fl", "rl"), ("fr", "rr"))),
    "no wz, ay sign": lambda frame: _without_rates(_scaled("ay", -1.0)(frame)),
    "no wz, ay in g": lambda frame: _without_rates(_scaled("ay", 1.0 / GRAVITY)(frame)),
}


def _from(frame: pd.DataFrame, share: float = 0.2) -> np.ndarray:
    """Rows from ``share`` of the log on."""
    return np.arange(len(frame)) >= int(share * len(frame))


def _stuck(frame: pd.DataFrame) -> pd.DataFrame:
    rows = _from(frame)
    return frame.assign(d_fl=np.where(rows, frame["d_fl"].to_numpy()[rows][0], frame["d_fl"]))


def _drifting(frame: pd.DataFrame) -> pd.DataFrame:
    t = frame["t"].to_numpy()
    start = t[_from(frame)][0]
    return frame.assign(d_fl=frame["d_fl"] + 0.001 * np.clip(t - start, 0.0, None))


def _dead(frame: pd.DataFrame) -> pd.DataFrame:
    rows = _from(frame)
    return frame.assign(d_fl=np.where(rows, np.nan, frame["d_fl"]),
                        v_fl=np.where(rows, np.nan, frame["v_fl"]))  # fmt: skip


def _dropout(frame: pd.DataFrame) -> pd.DataFrame:
    t = frame["t"].to_numpy()
    start = t[_from(frame)][0]
    gap = (t > start) & (t < start + 2.0)
    columns = ["ax", "ay", "az", *TRAVEL]
    return frame.assign(**{c: np.where(gap, np.nan, frame[c]) for c in columns})


def _spikes(frame: pd.DataFrame) -> pd.DataFrame:
    rng = np.random.default_rng(0)
    size = {"vx": 30.0, "ax": 50.0, "ay": 100.0, "az": 50.0}
    changed = {}
    for column in ("vx", "ax", "ay", "az", *TRAVEL):
        values = frame[column].to_numpy().copy()
        values[rng.choice(len(values), 5, replace=False)] += size.get(column, 0.2)
        changed[column] = values
    return frame.assign(**changed)


#: Sensor faults (issue 8's fault-injection set): not wiring mistakes, so the
#: checks at load must let them through to the filter's fault detection.
FAULTS: dict[str, Callable[[pd.DataFrame], pd.DataFrame]] = {
    "stuck d_fl": _stuck,
    "d_fl drifting 1 mm/s": _drifting,
    "dead d_fl": _dead,
    "ay bias 0.5 m/s^2": lambda frame: frame.assign(ay=frame["ay"] + 0.5),
    "2 s dropout": _dropout,
    "single-sample spikes": _spikes,
}


def report_of(frame: pd.DataFrame) -> WiringReport:
    """:func:`check_wiring` on a log frame's columns."""
    rates = frame[["wx", "wy", "wz"]].to_numpy() if "wz" in frame.columns else None
    return check_wiring(
        frame["t"].to_numpy(),
        frame["vx"].to_numpy(),
        frame[["ax", "ay", "az"]].to_numpy(),
        frame[list(TRAVEL)].to_numpy(),
        rates,
    )


def wiring_margins(paths: list[Path]) -> pd.DataFrame:
    """One row per log and corruption: caught or not, the diagnosis, every decided statistic."""
    rows = []
    for path in paths:
        frame = pd.read_csv(path) if path.suffix == ".csv" else pd.read_parquet(path)
        for name, corrupt in {"clean": lambda f: f, **CORRUPTIONS}.items():
            report = report_of(corrupt(frame))
            row = {"log": path.stem, "case": name, "caught": bool(report.diagnosis),
                   "diagnosis": report.diagnosis}  # fmt: skip
            row.update({c.name: np.nan if c.outcome is Outcome.UNDECIDED else c.statistic
                        for c in report.checks})  # fmt: skip
            rows.append(row)
    return pd.DataFrame(rows)


def margins(table: pd.DataFrame) -> pd.DataFrame:
    """Per case: logs caught, and the decisive statistics' extremes over the logs.

    ``sign min`` is the smallest decided sign agreement (partial correlation
    times the expected sign: fails below -0.3); ``lon``/``lat`` are the
    kinematic ratios dvx/dt : ax and vx wz : ay (1 when right); ``roll`` the
    left-right travel difference per m/s^2 of ay without a yaw rate (fails
    above 0.03 m).
    """
    signs = [c for c in table.columns if c.startswith("d_")]
    rows = []
    for case, group in table.groupby("case", sort=False):
        agreement = group[signs]
        row = {"case": case, "caught": f"{int(group['caught'].sum())}/{len(group)}",
               "sign min": agreement.min(axis=1).min(),
               "sign max": agreement.max(axis=1).max()}  # fmt: skip
        for name, column in (("lon", "dvx/dt against ax"), ("lat", "vx wz against ay"),
                             ("roll", "roll travel per ay")):  # fmt: skip
            values = group[column].dropna() if column in group else pd.Series(dtype=float)
            row[f"{name} min"] = values.min() if len(values) else np.nan
            row[f"{name} max"] = values.max() if len(values) else np.nan
        rows.append(row)
    return pd.DataFrame(rows).set_index("case")


def main(argv: list[str]) -> int:
    table = wiring_margins([Path(p) for p in argv])
    pd.set_option("display.width", 250, "display.max_columns", 40, "display.max_colwidth", 200)
    print(table[["log", "case", "caught", "diagnosis"]].to_string(index=False))
    print(margins(table).round(3).to_string())
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
