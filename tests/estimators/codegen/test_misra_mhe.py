"""MISRA C:2012: the embedded MHE's driver (wheelload_mhe.c, from templates/mhe_*.c) and its
timed runner carry no required finding that the deviation record written beside them does not
list, for the plain and the window driver, soft and hard, with and without a lag (cppcheck's
MISRA add-on, real files). OSQP's sources and the linked filter are checked elsewhere (OSQP's:
adopted code; the filter: test_misra_library.py). Skipped where cppcheck is not installed.
"""

from __future__ import annotations

import pytest

from wheelload.estimators.codegen.mhe import RUNNER, generate_mhe
from wheelload.estimators.codegen.misra import analyse, cppcheck
from wheelload.estimators.mhe.settings import (
    BiasStates,
    Constraint,
    Loss,
    MheSettings,
    ResidualLoss,
)
from wheelload.models import example_vehicle_path, load_vehicle

pytestmark = [
    pytest.mark.heavy(40),  # seconds (tests/conftest.py)
    pytest.mark.skipif(
        cppcheck() is None, reason="cppcheck not installed (apt-get install cppcheck)"
    ),
]

HUBER = ResidualLoss(kind=Loss.HUBER, threshold=2.0)
CASES = {
    "plain-soft": MheSettings(),
    "window-soft-l1-huber-acceleration-bias-lag-1": MheSettings(
        horizon=5,
        suspension_loss=ResidualLoss(kind=Loss.L1),
        constraint_loss=HUBER,
        bias_states=BiasStates.ACCELERATION,
        lag=1,
    ),
    "window-hard-l1-travel-bias-lag-1": MheSettings(
        horizon=5,
        bounded=True,
        constraint=Constraint.HARD,
        bias_states=BiasStates.TRAVEL,
        suspension_loss=ResidualLoss(kind=Loss.L1),
        lag=1,
    ),
    "plain-hard-lag-3": MheSettings(horizon=6, bounded=True, constraint=Constraint.HARD, lag=3),
}


@pytest.mark.parametrize("name", list(CASES))
def test_mhe_driver_has_no_open_required_finding(tmp_path, name):
    path = example_vehicle_path()
    folder = generate_mhe(load_vehicle(path), CASES[name], tmp_path, 0.01, vehicle_path=path)
    report = analyse(folder, [folder / "wheelload_mhe.c", folder / RUNNER])
    driver = {"wheelload_mhe.c", RUNNER}
    assert [f for f in report.required_open() if f.file in driver] == []
    # The runner alone asks for POSIX; the driver deviates only where its sizes (W = 1 with
    # the hard constraint, ND = 0 with acceleration biases alone) make index arithmetic trivial.
    deviated = {(f.file, f.rule) for f in report.findings if report.deviated(f)}
    trivial = {("wheelload_mhe.c", "2.2")} if "hard" in name or "acceleration" in name else set()
    assert {d for d in deviated if d[0] in driver} <= {
        (RUNNER, "21.1"),
        (RUNNER, "21.10"),
        *trivial,
    }
