"""The plant's tyre-force channels: logged, read back, and true to Newton's second law.

One iso-dlc run (about 4 s on the plant, its compiled chunk cached).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators.logs.signals import read_log, signals_from_frame
from wheelload.models import ModelParameters, load_vehicle
from wheelload.models.aero import aero_forces
from wheelload.models.vehicle.file import example_vehicle_path
from wheelload.studies.drive.scenario_log import LOG_COLUMNS, WHEEL_COLUMNS, write_log
from wheelload.studies.drive.scenario_runner import run_scenario


@pytest.fixture(scope="module")
def dlc():
    return run_scenario("iso-dlc", example_vehicle_path())


def test_tyre_forces_sum_to_the_body_force(dlc):
    """Tyre-frame fx, fy rotated by the steer and summed equal m a of the CG (ISO 8855).

    Lateral: within 0.5 % of its RMS (the body's roll tilts the normal loads by
    ~1 % of them into body y). Longitudinal: the sum also carries the drag; within
    10 % of its RMS once the drag is added (the pitch tilt of the loads, ~10 N).
    """
    f = dlc.truth.frame
    vehicle = load_vehicle(example_vehicle_path())
    fx = f[[f"fx_{w}" for w in ("fl", "fr", "rl", "rr")]].to_numpy()
    fy = f[[f"fy_{w}" for w in ("fl", "fr", "rl", "rr")]].to_numpy()
    c, s = np.cos(f["steer"].to_numpy()), np.sin(f["steer"].to_numpy())
    sum_x = (fx[:, 0] + fx[:, 1]) * c - (fy[:, 0] + fy[:, 1]) * s + fx[:, 2] + fx[:, 3]
    sum_y = (fy[:, 0] + fy[:, 1]) * c + (fx[:, 0] + fx[:, 1]) * s + fy[:, 2] + fy[:, 3]
    m = vehicle.mass.total
    _, drag = aero_forces(f["vx"].to_numpy(), ModelParameters.from_vehicle(vehicle))
    rms = lambda x: float(np.sqrt(np.mean(np.square(x))))  # noqa: E731
    assert rms(sum_y - m * f["ay_cg"]) < 0.005 * rms(sum_y)
    assert rms(sum_x - drag - m * f["ax_cg"]) < 0.1 * rms(sum_x)
    # A left turn needs force to the left (+y): the lane change's first turn is left.
    first = np.argmax(np.abs(sum_y) > 2000.0)
    assert np.sign(sum_y[first]) == np.sign(f["ay_cg"].iloc[first])


def test_wheel_channels_written_and_read(dlc, tmp_path):
    """The log holds the wheel columns after the load columns; the reader takes them."""
    path = tmp_path / "dlc.csv"
    write_log(dlc.log, path, dlc.metadata)
    frame = pd.read_csv(path)
    assert tuple(frame.columns) == LOG_COLUMNS + WHEEL_COLUMNS
    signals = read_log(path, wiring_checks=False)
    assert signals.spin.shape == signals.torque.shape == (len(frame), 4)
    np.testing.assert_allclose(signals.reference_fy[:, 3], frame["fy_rr"], rtol=1e-8)
    # Spins are measured (0.02 rad/s noise), torques and the steer are logged clean.
    noise = signals.spin[:, 0] - dlc.truth.frame["omega_fl"].to_numpy()
    assert 0.01 < np.std(noise) < 0.03
    # A log without them still reads, the channels None.
    old = signals_from_frame(frame[list(LOG_COLUMNS)], wiring_checks=False)
    assert old.spin is None and old.reference_fx is None and old.steer is None


def test_estimate_reports_the_tyre_force_errors(dlc, tmp_path, capsys):
    """``estimate --method tyre-forces`` writes fx_*, fy_* and prints their pooled error
    against the log's reference, the figures of an independent computation on the same run
    (to the printed 0.1 %)."""
    from wheelload.estimators.registry import build
    from wheelload.studies.cli import main

    path, out = tmp_path / "dlc.csv", tmp_path / "forces.csv"
    write_log(dlc.log, path, dlc.metadata)
    vehicle = str(example_vehicle_path())
    code = main(["estimate", str(path), "--vehicle", vehicle, "--method", "tyre-forces",
                 "--out", str(out)])  # fmt: skip
    assert code == 0
    printed = capsys.readouterr().out
    written = pd.read_csv(out)
    signals = read_log(path, wiring_checks=False)
    estimate = build("tyre-forces", load_vehicle(vehicle)).run(signals)
    for axis, reference in (("x", signals.reference_fx), ("y", signals.reference_fy)):
        values = written[[f"f{axis}_{w}" for w in ("fl", "fr", "rl", "rr")]].to_numpy()
        np.testing.assert_allclose(values, getattr(estimate, f"f{axis}"), atol=1e-6)
        share = 100 * np.sqrt(np.mean((values - reference) ** 2) / np.mean(reference**2))
        assert f"tyre force F_{axis} against the log's reference" in printed
        assert f"({share:.1f} % of its RMS" in printed


def test_compare_scores_the_tyre_forces(dlc):
    """``compare`` with tyre methods: their F_x, F_y RMSE per wheel and pooled and the % of
    the reference RMS, each equal to a plain computation on the same estimate (1e-12
    relative); methods without tyre forces get no rows, and the block is F_x then F_y."""
    from wheelload.estimators.registry import build
    from wheelload.studies.pipeline.comparison import compare_methods, format_table

    signals = signals_from_frame(dlc.log, wiring_checks=False)
    vehicle = load_vehicle(example_vehicle_path())
    comparison = compare_methods(signals, vehicle, ("kf", "tyre-forces", "tyre-rigid"), repeat=1)
    rows = {r.info.name: dict(r.forces) for r in comparison.results}
    assert rows["kf"] == {}
    estimate = build("tyre-rigid", vehicle).run(signals)
    for axis, values, reference in (("F_x", estimate.fx, signals.reference_fx),
                                    ("F_y", estimate.fy, signals.reference_fy)):  # fmt: skip
        errors = values - reference
        expected = [*np.sqrt(np.mean(errors**2, axis=0)), np.sqrt(np.mean(errors**2))]
        expected.append(100 * expected[-1] / np.sqrt(np.mean(reference**2)))
        np.testing.assert_allclose(rows["tyre-rigid"][axis], expected, rtol=1e-12)
        assert rows["tyre-forces"][axis][5] < rows["tyre-rigid"][axis][5]
    text = format_table(comparison)
    assert text.index("F_x       tyre-forces") < text.index("F_y       tyre-forces")
