"""The generated C's time-stamped step: an ordinary call against the worst case, a full rewind.

A C program linked with the library (double, runtime parameters, the strict flags, the default
ring of ``PREFIX_N_CHECKPOINTS``) times, in each of ``rounds`` rounds,

- ``step``: ``wheelload_kf_step``, the synchronous step, on the bundled example log's samples;
- ``in order``: ``wheelload_kf_step_at`` with each sample a measurement newer than the last
  (no rewind: one step and a checkpoint);
- ``full rewind``: ``wheelload_kf_step_at`` with a measurement of the oldest checkpoint's time
  stamp on a full ring (merged there: every checkpoint filtered again), the worst case of
  one call;

each as seconds per call: in each round the fastest of :data:`BATCHES` batches (the mean call
of a batch; a batch the scheduler interrupted is left out). The ratios to ``step`` are taken
per round and given min / median / max over the rounds. Printed, never asserted.
"""

from __future__ import annotations

import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wheelload.estimators import read_log
from wheelload.estimators.codegen.kf import CodegenOptions, build_program, generate
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.models import example_vehicle_path
from wheelload.studies.bench.c_clock import SECONDS
from wheelload.studies.pipeline.example_log import example_log_path

#: Batches per round (the fastest counts) and full rewinds in a batch.
BATCHES = 8
REWINDS = 4

PROGRAM = (
    SECONDS
    + r"""
#include <stdio.h>
#include <stdlib.h>
#include "wheelload_kf.h"

#define REWINDS @REWINDS@
#define BATCHES @BATCHES@
#define SAMPLES_PER_BATCH 256

/* argv: samples file (interval, then one sample of N_INPUTS values a line), rounds. */
int main(int argc, char **argv)
{
    static wheelload_kf_timed timed;
    static wheelload_kf_input samples[4000];
    wheelload_kf_params params = wheelload_kf_default_params;
    wheelload_kf_state state;
    wheelload_kf_output out;
    const uint32_t all = (1u << WHEELLOAD_KF_N_INPUTS) - 1u;
    double interval, t = 0.0, sink = 0.0;
    int n = 0, k, round, rounds;
    FILE *in;
    if (argc != 3 || (in = fopen(argv[1], "r")) == NULL) {
        return 2;
    }
    rounds = atoi(argv[2]);
    if (fscanf(in, "%lf", &interval) != 1) {
        return 2;
    }
    while (n < 4000) {
        for (k = 0; k < WHEELLOAD_KF_N_INPUTS; ++k) {
            if (fscanf(in, "%lf", wheelload_kf_input_field(&samples[n], k)) != 1) {
                break;
            }
        }
        if (k < WHEELLOAD_KF_N_INPUTS) {
            break;
        }
        ++n;
    }
    fclose(in);
    if (n < 2 * SAMPLES_PER_BATCH || SAMPLES_PER_BATCH < WHEELLOAD_KF_N_CHECKPOINTS
        || wheelload_kf_init(&state, &params) != 0
        || wheelload_kf_timed_init(&timed, &params, interval, 1e9, 1.0) != 0) {
        return 3;
    }
    printf("checkpoints %d\n", WHEELLOAD_KF_N_CHECKPOINTS);
    for (round = 0; round < rounds; ++round) {
        /* Per kind the fastest of BATCHES batches (a batch a preemption hit is left out). */
        double step = 1e9, ordered = 1e9, rewind = 1e9;
        int batch;
        for (batch = 0; batch < BATCHES; ++batch) {
            const int first = (batch * SAMPLES_PER_BATCH) % (n - SAMPLES_PER_BATCH);
            double start = seconds(), elapsed;
            for (k = first; k < first + SAMPLES_PER_BATCH; ++k) {
                wheelload_kf_step(&state, &params, &samples[k], interval, &out);
                sink += out.loads[0];
            }
            elapsed = (seconds() - start) / SAMPLES_PER_BATCH;
            step = elapsed < step ? elapsed : step;
            start = seconds();
            for (k = first; k < first + SAMPLES_PER_BATCH; ++k) {
                t += interval;
                wheelload_kf_step_at(&timed, &params, &samples[k], all, t, &out);
                sink += out.loads[0];
            }
            elapsed = (seconds() - start) / SAMPLES_PER_BATCH;
            ordered = elapsed < ordered ? elapsed : ordered;
            /* The ring is full: a measurement of the oldest checkpoint's time stamp. */
            start = seconds();
            for (k = first; k < first + REWINDS; ++k) {
                const double oldest = timed.ring[timed.head].t;
                wheelload_kf_step_at(&timed, &params, &samples[k], all, oldest, &out);
                sink += out.loads[0];
            }
            elapsed = (seconds() - start) / REWINDS;
            rewind = elapsed < rewind ? elapsed : rewind;
        }
        printf("round %.9g %.9g %.9g %lu\n", step, ordered, rewind,
               (unsigned long)timed.replayed);
    }
    fprintf(stderr, "%g\n", sink);
    return 0;
}
"""
)


@dataclass(frozen=True)
class TimedStepTimes:
    """Seconds per call, one entry per round (module docstring), and the ring's size."""

    checkpoints: int
    step: list[float]
    in_order: list[float]
    full_rewind: list[float]
    replayed: list[float]  # steps filtered again per full rewind (checkpoints - 1)


def time_timed_step(rounds: int, folder: Path | None = None) -> TimedStepTimes:
    """Build the library and the timing program (in ``folder``, default a temporary one) and
    run it for ``rounds`` rounds on the bundled example log."""
    signals = read_log(example_log_path())
    inputs = input_matrix(signals).T[:4000]
    interval = float(np.median(np.diff(signals.t)))
    with tempfile.TemporaryDirectory() as temporary:
        where = Path(folder or temporary)
        library = generate(example_vehicle_path(), where, CodegenOptions(sample_interval=interval))
        main = where / "timed_bench.c"
        main.write_text(
            PROGRAM.replace("@REWINDS@", str(REWINDS)).replace("@BATCHES@", str(BATCHES))
        )
        binary = build_program(library, main, where / "timed_bench")
        data = where / "samples.txt"
        rows = "\n".join(" ".join(repr(float(v)) for v in row) for row in inputs)
        data.write_text(f"{interval!r}\n{rows}\n".replace("nan", "NAN"))
        done = subprocess.run([str(binary), str(data), str(rounds)], capture_output=True,
                              text=True, check=True)  # fmt: skip
    lines = done.stdout.split("\n")
    checkpoints = int(lines[0].split()[1])
    measured = np.array([[float(v) for v in line.split()[1:5]] for line in lines[1:] if line])
    step, in_order, full_rewind, replayed = measured.T
    per_rewind = np.diff(np.concatenate([[0.0], replayed])) / (REWINDS * BATCHES)
    return TimedStepTimes(checkpoints, list(step), list(in_order), list(full_rewind),
                          list(per_rewind))  # fmt: skip
