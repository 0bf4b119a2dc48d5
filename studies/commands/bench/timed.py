"""``wheelload bench timed``: the generated C's time-stamped step, ordinary and worst case.

Prints, over ``--repeats`` rounds, the seconds per call of the synchronous ``wheelload_kf_step``,
of ``wheelload_kf_step_at`` with measurements in order, and of its worst case, a rewind of
the full ring of checkpoints (:mod:`~wheelload.studies.bench.timed_step`), and their ratios
to the synchronous step (min / median / max). Printed, never asserted.
"""

from __future__ import annotations

import argparse

from wheelload.studies.bench.step_timing import spread
from wheelload.studies.bench.timed_step import time_timed_step


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench timed``."""
    parser = subparsers.add_parser("timed")
    parser.add_argument("--repeats", type=int, default=15, help="rounds timed (default 15)")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.repeats < 1:
        raise ValueError("--repeats must be >= 1")
    print("timed C step (wheelload_kf_step_at), double, runtime parameters, strict flags; "
          "bundled example log")  # fmt: skip
    times = time_timed_step(args.repeats)
    ring = times.checkpoints
    print(f"  ring of {ring} checkpoints (a full rewind filters the merged measurement and "
          f"{min(times.replayed):.0f} more); per call, over {args.repeats} rounds, "
          "min / median / max")  # fmt: skip
    rows = (
        ("wheelload_kf_step (synchronous) [us]", times.step),
        ("step_at, in order [us]", times.in_order),
        (f"step_at, full rewind ({ring} steps) [us]", times.full_rewind),
    )
    for label, seconds in rows:
        print(f"  {label:<40} {spread([1e6 * s for s in seconds])}")
    ordered = [o / s for o, s in zip(times.in_order, times.step, strict=True)]
    worst = [w / s for w, s in zip(times.full_rewind, times.step, strict=True)]
    print(f"  {'step_at in order / step':<40} {spread(ordered)}")
    print(f"  {'worst case (full rewind) / step':<40} {spread(worst)}")
    fastest = min(times.full_rewind) / min(times.step)
    print(f"  {'fastest full rewind / fastest step':<40} {fastest:.3g}")
    return 0
