"""The timed-step benchmark measures what it names: the worst case is a rewind of the whole
ring (every checkpoint but the merged one filtered again, counted by the C itself), and each
timing is a positive time per call (their values are printed, never asserted)."""

import numpy as np
from c_parity import needs_gcc

from wheelload.studies.bench.timed_step import time_timed_step


@needs_gcc
def test_the_worst_case_timed_is_a_rewind_of_the_full_ring(tmp_path):
    times = time_timed_step(2, tmp_path)
    assert times.checkpoints == 64
    assert times.replayed == [times.checkpoints - 1] * 2
    for column in (times.step, times.in_order, times.full_rewind):
        assert len(column) == 2 and np.all(np.array(column) > 0)
