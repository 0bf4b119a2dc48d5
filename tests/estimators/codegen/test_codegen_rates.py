"""The generated example reads the body-rate derivatives, it does not derive them.

wheelload's Python reader derives ``wx_dot wy_dot wz_dot`` from ``wx wy wz``
(:func:`~wheelload.estimators.logs.signals.rate_derivatives`) when a log has the
rates only; the C example (documented in its header) treats the absent
derivative columns as missing samples, so the inertia terms that need them
are dropped and flagged. Pinned here: on a log with rates and no derivatives
the C equals the Python filter run with the derivatives missing (1e-9
relative, as tests/estimators/codegen/test_codegen.py), and differs from the Python filter that
derived them.
"""

import dataclasses
import subprocess

import numpy as np
import pandas as pd

from wheelload.estimators import TwoStageKF, read_log, write_log
from wheelload.estimators.codegen.kf import CodegenOptions, build_program, generate
from wheelload.estimators.result import WHEELS
from wheelload.models import example_vehicle_path
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

LOADS = [f"fz_{w}" for w in WHEELS]


def test_example_drops_the_rate_terms_python_derives(vehicle, tmp_path):
    signals = synthetic_log(
        vehicle, slalom(duration=6.0), noise=SensorNoise(acceleration=0.05, travel=0.0003)
    )
    t = signals.t
    w = 2 * np.pi * 0.4
    rates = np.column_stack(
        [-0.3 * np.cos(w * t), 0.2 * np.sin(w * t), signals.acc[:, 1] / signals.vx]
    )
    signals = dataclasses.replace(signals, rates=rates, rate_dots=None)
    log = tmp_path / "rates_only.csv"
    write_log(signals, log)
    assert not {"wx_dot", "wy_dot", "wz_dot"} & set(pd.read_csv(log).columns)

    library = generate(example_vehicle_path(), tmp_path / "c", CodegenOptions())
    binary = build_program(library, library.example, tmp_path / "c" / "example")
    out = tmp_path / "estimates.csv"
    subprocess.run([str(binary), str(log), str(out)], check=True, timeout=60)
    c = pd.read_csv(out)

    read = read_log(log)
    derived = TwoStageKF(vehicle).run(read)
    missing = TwoStageKF(vehicle).run(
        dataclasses.replace(read, rate_dots=np.full((len(read), 3), np.nan))
    )
    scale = np.abs(missing.loads).max()
    np.testing.assert_allclose(c[LOADS], missing.loads, rtol=1e-9, atol=1e-9 * scale)
    np.testing.assert_array_equal(c["status"], missing.flags)
    # The derived derivatives feed the body-inertia terms: other loads, other flags.
    assert np.abs(derived.loads - missing.loads).max() > 1.0  # N
    assert (derived.flags != missing.flags).any()
