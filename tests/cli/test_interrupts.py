"""One Ctrl-C stops a plant simulation or a long MHE run: one line, status 130, no output.

The plant's CasADi call checks for signals and sometimes swallowed the KeyboardInterrupt:
the simulation then ran to its end (status 0) or failed on the ``None`` it got back
(status 1, a traceback); before the fix 3 of 8 presses at random times were lost.
Two presses at fixed times into the Nordschleife lap (about 11 s of stepping): ~7 s.

OSQP's solve catches SIGINT with a handler of its own and returns the status
"interrupted": Python never saw the press, and the MHE took that sample's QP as failed
(the filter's estimate) and ran on; before the fix 1 of 6 presses into the MHE's window
loop was lost (models/runtime/interrupts.py). Two presses into a 135 300-sample MHE run and
one into a long OSQP solve: ~12 s.
"""

import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import osqp
import pandas as pd
import pytest
import scipy.sparse as sp

from wheelload.models import example_vehicle_path
from wheelload.studies.pipeline.example_log import example_log_path

pytestmark = pytest.mark.heavy(25)  # seconds (tests/conftest.py)

#: The command with Ctrl-C's default handling, also where this test runs with SIGINT
#: ignored (a background job of a shell inherits SIG_IGN, which Python then keeps).
INTERRUPTIBLE = [sys.executable, "-c", "import runpy, signal, sys; "
                 "signal.signal(signal.SIGINT, signal.default_int_handler); "
                 "sys.argv[0] = 'wheelload'; "
                 "runpy.run_module('wheelload.studies.cli', run_name='__main__')"]  # fmt: skip


def _press(argv: list[str], after: float, out) -> None:
    """``wheelload ARGV`` pressed Ctrl-C once, ``after`` seconds in: the line, 130, no ``out``."""
    run = subprocess.Popen([*INTERRUPTIBLE, *argv, "--out", str(out)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    time.sleep(after)
    assert run.poll() is None, run.communicate()
    run.send_signal(signal.SIGINT)
    _, err = run.communicate(timeout=600)  # a guard against a hang, not a speed check
    assert run.returncode == 130, err
    assert err == f"wheelload {argv[0]}: interrupted\n"
    assert not out.exists()


@pytest.mark.parametrize("after", [2.0, 3.5])
def test_one_press_stops_a_simulation(tmp_path, after):
    _press(["simulate", "nordschleife"], after, tmp_path / "lap.csv")


@pytest.fixture(scope="module")
def long_log(tmp_path_factory):
    """The bundled log 100 times over at 100 Hz (135 300 samples, ~23 min of driving)."""
    frame = pd.read_csv(example_log_path(), comment="#")
    frame = pd.concat([frame] * 100, ignore_index=True)
    frame["t"] = 0.01 * (np.arange(len(frame)) + 1)
    path = tmp_path_factory.mktemp("long") / "long.csv"
    frame.to_csv(path, index=False)
    return path


@pytest.mark.parametrize("after", [2.5, 6.0])  # the MHE's CasADi terms; its window loop
def test_one_press_stops_a_long_mhe_run(tmp_path, long_log, after):
    argv = ["estimate", str(long_log), "--method", "mhe", "--vehicle", str(example_vehicle_path())]
    _press(argv, after, tmp_path / "loads.csv")


def test_a_press_osqp_caught_is_raised():
    """A real press during a long OSQP solve: OSQP's handler takes it (Python's never runs)
    and the solve returns INTERRUPTED, which :func:`check_interrupted` raises."""
    from wheelload.estimators.mhe.qp import INTERRUPTED, check_interrupted

    n = 1000  # a QP that runs to its iteration limit (tolerances far below rounding)
    M = sp.random(n, n, density=0.01, random_state=0)
    A = sp.random(2 * n, n, density=0.01, random_state=1)
    solver = osqp.OSQP()
    solver.setup(P=sp.csc_matrix(M @ M.T + sp.eye(n)), q=np.ones(n), A=sp.csc_matrix(A),
                 l=-np.ones(2 * n), u=np.ones(2 * n), verbose=False, max_iter=10**9,
                 eps_abs=1e-300, eps_rel=1e-300)  # fmt: skip
    seen = []  # presses Python's handler got
    previous = signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    press = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    try:
        press.start()
        status = solver.solve(raise_error=False).info.status_val
    finally:
        press.join()
        signal.signal(signal.SIGINT, previous)
    assert (status, seen) == (INTERRUPTED, [])
    with pytest.raises(KeyboardInterrupt):
        check_interrupted(status)
