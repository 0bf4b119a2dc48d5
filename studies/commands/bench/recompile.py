"""``wheelload bench recompile``: vehicle-file edit → many-logs run, before and after.

Over ``--repeats`` repeats, each with a new value edit of a copy of the vehicle file (a
comment line and the front spring rate, :func:`~wheelload.studies.bench.recompile.edited_copy`),
prints the seconds from the edited file to the estimates of ``--log-count`` copies of the bundled
example log (min / median / max) for the many-logs library keyed by the model structure
(after) and by the generated text (before: a compile per edit), each as a ratio against the
single-log estimate of the same file in the same repeat, and after / before. The first build
of the structure is made (or loaded) before the repeats and printed apart. ``--after-only``
leaves out the text-keyed way (a compile of about a minute per repeat).

Printed, never asserted.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from wheelload.estimators import read_log
from wheelload.estimators.codegen.batched import run_batched
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import load_vehicle
from wheelload.studies.bench.recompile import edited_copy, time_edit
from wheelload.studies.bench.step_timing import spread
from wheelload.studies.commands.options import add_vehicle_option, vehicle_file
from wheelload.studies.pipeline.example_log import example_log_path

#: Seconds from a value edit to the many-logs estimates (issue 43's target).
TARGET = 3.0


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench recompile``."""
    parser = subparsers.add_parser("recompile")
    add_vehicle_option(parser)
    parser.add_argument("--repeats", type=int, default=3, help="rounds: edits timed (default 3)")
    parser.add_argument(
        "--log-count", dest="logs", type=int, default=5, metavar="N",
        help="number of logs: copies of the example log in the run (default 5)",
    )  # fmt: skip
    parser.add_argument(
        "--after-only", action="store_true", help="leave out the text-keyed library (before)"
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.repeats < 1 or args.logs < 2:
        raise ValueError("--repeats >= 1 and --log-count >= 2 are needed")
    vehicle_path = vehicle_file(args)
    log = read_log(example_log_path())
    logs = [log] * args.logs
    name = load_vehicle(vehicle_path, allow_unusual=True).name
    print(f"recompile, {name}: vehicle-file edit -> {args.logs} logs of {len(log)} samples")
    start = time.perf_counter()
    run_batched(TwoStageKF(load_vehicle(vehicle_path, allow_unusual=True)), vehicle_path, logs)
    first = time.perf_counter() - start
    print(f"  first run of this model structure (built or loaded): {first:.3g} s")
    times = []
    with tempfile.TemporaryDirectory() as folder:
        for repeat in range(args.repeats):
            edited = edited_copy(vehicle_path, Path(folder), repeat)
            times.append(time_edit(edited, logs, text=not args.after_only))
    single = [t.single for t in times]
    after = [t.structure for t in times]
    print(f"  each over {args.repeats} edits, min / median / max")
    print(f"  single-log estimate (TwoStageKF.run, one log) [s]: {spread(single)}")
    print(f"  after: keyed by the model structure [s]:          {spread(after)} "
          f"(target <= {TARGET:g} s)")  # fmt: skip
    print(f"    / single-log estimate: {spread([a / s for a, s in zip(after, single)])}")
    if not args.after_only:
        before = [t.text for t in times if t.text is not None]
        print(f"  before: keyed by the generated text [s]:          {spread(before)}")
        print(f"    / single-log estimate: {spread([b / s for b, s in zip(before, single)])}")
        print(f"  after / before: {spread([a / b for a, b in zip(after, before)])}")
    return 0
