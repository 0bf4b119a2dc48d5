"""The fleet benchmark's peers compute the filter's numbers.

The batched NumPy update and the numba loop (``studies/bench/fleet_peers.py``) run the
same prediction and Joseph-form updates as the two-stage KF on logs where no guard fires
and the mass is the file's (payload filter off): each window's loads must equal
:meth:`TwoStageKF.run` on that window to 1e-9 relative to the largest load (the same
equations in another order of operations: measured about 1e-15; 1e-9 is the stacked
update's tolerance in ``tests/estimators/kf/test_two_stage.py``).
"""

import numpy as np
import pytest

from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.studies.bench.fleet import fixed_mass, make_fleet, peer_arrays
from wheelload.studies.bench.fleet_peers import numba_fleet, numpy_fleet

pytestmark = pytest.mark.heavy(10)  # seconds (tests/conftest.py)

TOLERANCE = 1e-9


@pytest.fixture(scope="module")
def fleet_case(vehicle):
    vehicle = fixed_mass(vehicle)
    kf = TwoStageKF(vehicle)
    fleet = make_fleet(vehicle, 3, 400)
    return kf, fleet, peer_arrays(kf, fleet)


def _check(kf, fleet, loads):
    for k, log in enumerate(fleet.logs):
        expected = kf.run(log).loads
        assert np.abs(loads[:, k] - expected).max() <= TOLERANCE * np.abs(expected).max()


def test_numpy_peer_equals_the_filter(fleet_case):
    kf, fleet, arrays = fleet_case
    _check(kf, fleet, numpy_fleet(arrays))


def test_numba_peer_equals_the_filter(fleet_case):
    # numba compiles the loop on first use (seconds): only where the bench extra is installed
    run = numba_fleet()
    if run is None:
        pytest.skip("numba not installed (the bench extra)")
    kf, fleet, arrays = fleet_case
    _check(kf, fleet, run(arrays))
