r"""Embedded MHE: OSQP's generated solver plus the generated QP-terms routine, in C.

The emitted folder holds OSQP's embedded code (``parameters="matrices"``) for
the window's QP, set up by :class:`~wheelload.estimators.mhe.MovingHorizonEstimator`
itself; ``wheelload_mhe_terms.c``, CasADi's C of the estimator's own terms
Function (:func:`wheelload.estimators.mhe_terms.terms_function`, the one the
Python MHE maps over a log), which maps one sample to its QP terms; and
``wheelload_mhe.c``, which keeps the window, assembles the Hessian values
(updated only when they change), :math:`q, l, u`, warm-starts and solves.

Input guarding: a non-finite input is treated as missing, as in the KF: the
suspension and equilibrium rows that depend on it (the filter's dependency
masks) are dropped from the sample's terms and reported in ``flags``.

Limits, against the Python MHE:

- steady-state arrival cost only (:attr:`Arrival.STEADY_STATE`), from tables;
- the cost scale and the steady-state arrival weight at the nominal interval
  given at generation (as Python's at its log's median interval); each
  sample's own interval sets its weights and random-walk link, and a
  non-positive or non-finite interval holds the estimate (flags 255), as in
  Python;
- hard constraints with a missing equilibrium input take :math:`A x` of the
  previous MHE estimate for that row, where Python takes the Kalman
  estimate of the same sample (there is no filter in the C);
- a sample whose QP is not solved keeps the previous estimate (Python: the
  Kalman estimate) and returns OSQP's status for the caller to act on; the
  newest loads are clipped to the bounds without Python's tolerance check;
- no standard deviations or residuals; the robust losses, bias states and
  lagged output of :mod:`wheelload.estimators.mhe_window` are Python only
  (``generate_mhe`` refuses them).

Precision: ``Precision.FLOAT`` generates OSQP with ``use_float`` (its
``osqp_configure.h`` defines ``OSQP_USE_FLOAT``; the program reports
``sizeof(OSQPFloat)``), the QP vectors in ``OSQPFloat``; the terms routine and
the window stay in double. Measured on the bundled plant log, N = 10,
bounded: float against double within 0.02 N (soft) and 3e-5 N (hard), every
QP solved, on x86-64 and on 32-bit ARM under qemu-arm
(``tests/test_cross_compiled.py``). :func:`build_mhe_program` builds a
stand-alone program (any compiler, e.g. ``arm-linux-gnueabihf-gcc -static``).

Example
-------
>>> library = build_mhe_library(vehicle, MheSettings(horizon=20), Path("build"), dt=0.01)
>>> result = library.run(signals)
"""

from __future__ import annotations

import ctypes
import dataclasses
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from wheelload.estimators.c_emitter import Precision
from wheelload.estimators.mhe import (
    Arrival,
    MheSettings,
    MovingHorizonEstimator,
    _csc_value_order,
)
from wheelload.estimators.mhe_terms import LOAD_SCALE, TERMS_NAME
from wheelload.estimators.output_files import atomic_write, check_output_folder
from wheelload.estimators.quiet import quiet_stdout
from wheelload.estimators.result import StepFlag
from wheelload.estimators.signals import Signals
from wheelload.estimators.two_stage import MAX_INTERVAL, input_matrix, sample_intervals
from wheelload.models import INPUTS, Vehicle


def _array(name: str, values, kind: str = "double") -> str:
    flat = np.asarray(values, dtype=float if kind == "double" else int).ravel()
    if kind != "double":
        body = ", ".join(str(int(v)) for v in flat)
    else:
        body = ", ".join(repr(float(v)) if np.isfinite(v) else ("1e30" if v > 0 else "-1e30")
                         for v in flat)  # fmt: skip
    return f"static const {kind} {name}[{max(flat.size, 1)}] = {{{body or '0'}}};\n"


def embedded_settings(settings: MheSettings) -> MheSettings:
    """The settings the embedded MHE realises: steady-state arrival."""
    return dataclasses.replace(settings, arrival=Arrival.STEADY_STATE)


def generate_mhe(
    vehicle: Vehicle,
    settings: MheSettings,
    folder: Path,
    dt: float,
    precision: Precision = Precision.DOUBLE,
    *,
    force: bool = False,
) -> Path:
    """Write the embedded MHE's C sources to ``folder`` (see module docstring).

    ``precision`` is OSQP's floating type (``OSQPFloat``: the solver, its
    matrices and the QP vectors); the terms routine and the window stay in
    double. ``folder`` must be new or empty unless ``force``; the files are
    generated in a temporary folder inside it and each is renamed into place
    once complete (:func:`~wheelload.estimators.output_files.atomic_write`), so
    an interrupted run leaves the old file or the new one, never a mix.
    """
    folder = Path(folder)
    check_output_folder(folder, [], force=force)
    folder.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".wheelload_mhe-", dir=folder))
    try:
        _generate_into(vehicle, settings, staging, dt, precision)
        for source in sorted(p for p in staging.rglob("*") if p.is_file()):
            target = folder / source.relative_to(staging)
            target.parent.mkdir(parents=True, exist_ok=True)
            with atomic_write(target, replace=force) as temporary:
                shutil.copyfile(source, temporary)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return folder


def _generate_into(
    vehicle: Vehicle, settings: MheSettings, folder: Path, dt: float, precision: Precision
) -> None:
    """Write every generated file into the (temporary) ``folder``."""
    if settings.extended:
        raise ValueError(
            "the embedded MHE supports the quadratic window only (no robust loss, no bias "
            "states); generate with the default losses and bias_states"
        )
    settings = embedded_settings(settings)
    mhe = MovingHorizonEstimator(vehicle, settings)
    N, width = settings.horizon, mhe.width
    state = mhe.initial_state(dt)
    P0 = mhe.filter.initial_state().P
    if not np.allclose(P0, P0[0, 0] * np.eye(4), rtol=0, atol=0):
        raise ValueError("the embedded MHE needs an isotropic initial covariance")
    with quiet_stdout():  # OSQP reports the files it writes
        mhe.workspace.solver.codegen(str(folder / "osqp"), prefix="wheelload_mhe_",
                                     parameters="matrices", force_rewrite=True,
                                     use_float=precision is Precision.FLOAT)  # fmt: skip
    function = mhe.terms
    generator = ca.CodeGenerator(f"{TERMS_NAME}.c", {"with_header": True})
    generator.add(function)
    generator.generate(str(folder) + "/")
    rows = N * width if settings.bounded else 0
    x0 = np.array(mhe.filter.parameters.static(), dtype=float)
    order = _csc_value_order(N, width)
    low, high = mhe.load_bounds
    header = "".join([
        f"#define N {N}\n#define W {width}\n#define NX (N * W)\n#define NY {max(rows, 1)}\n",
        f"#define HAS_Y {int(rows > 0)}\n#define HARD {int(mhe.hard)}\n",
        f"#define NNZ {order.size}\n#define NP {mhe.p.size}\n",
        f"#define SZ_ARG {function.sz_arg()}\n#define SZ_RES {function.sz_res()}\n",
        f"#define SZ_IW {function.sz_iw()}\n#define SZ_W {function.sz_w()}\n",
        f"#define LOAD_SCALE {LOAD_SCALE!r}\n#define DT {float(dt)!r}\n",
        f"#define Q_DENSITY {float(mhe.tuning[0])!r}\n#define P0_VAR {float(P0[0, 0])!r}\n",
        f"#define MAX_INTERVAL {float(MAX_INTERVAL)!r}\n",
        f"#define COST {float(state.cost)!r}\n#define RHO0 {float(settings.solver.rho)!r}\n",
        f"#define LOW_LOAD {float(max(low, -1e30))!r}\n",
        f"#define HIGH_LOAD {float(min(high, 1e30))!r}\n",
        f"#define N_INPUTS {len(INPUTS)}\n#define N_USED {len(StepFlag.update_flags())}\n",
        "static const unsigned UPDATE_FLAGS[N_USED] = {"
        + ", ".join(f"{flag.value}u" for flag in StepFlag.update_flags())
        + "};\n",
        _array("ORDER", order, "int"),
        _array("ARRIVAL_STEADY", state.steady),
        _array("P_VECTOR", mhe.p),
        _array("TUNING", mhe.tuning),
        _array("NULL_VECTOR", mhe.null),
        _array("X0", x0),
    ])  # fmt: skip
    (folder / "wheelload_mhe.c").write_text(header + DRIVER)


DRIVER = r"""
#include <math.h>
#include <string.h>
#include <time.h>
#include "osqp.h"
#include "wheelload_mhe_workspace.h"
#include "wheelload_mhe_terms.h"

/* The window, oldest sample first: the terms of wheelload_mhe_terms (QP units). */
static double HB[N][W * W], G[N][W], LINK[N], DRIFT[N], XP[N][4], LO[N][W], HI[N][W];
static double HIST[N][4];
static OSQPFloat XW[NX], YW[NY], Q[NX], L[NX + 1], U[NX + 1], PX[NNZ]; /* OSQP's type */
static double VALUES[N * W * W + (N - 1) * W]; /* diagonal blocks, then couplings */
static long K = 0;
static double ARRIVAL_FIRST[16]; /* c s^2 (P0 + q dt_0 I)^-1 of the log's first interval */

void wheelload_mhe_reset(void) {
    K = 0;
    memset(XW, 0, sizeof XW);
    memset(YW, 0, sizeof YW);
    memset(HB, 0, sizeof HB);
    memset(G, 0, sizeof G);
    memset(LINK, 0, sizeof LINK);
    memset(DRIFT, 0, sizeof DRIFT);
    memset(XP, 0, sizeof XP);
    memset(LO, 0, sizeof LO);
    memset(HI, 0, sizeof HI);
    for (int j = 0; j < N; ++j) {
        for (int a = 0; a < W; ++a) HB[j][a * W + a] = 1.0; /* inert samples before the log */
        memcpy(HIST[j], X0, sizeof X0);
    }
    osqp_update_rho(&wheelload_mhe_solver, RHO0);
}

static void shift(double *rows, const double *value, int width) {
    memmove(rows, rows + width, sizeof(double) * (size_t)(width * (N - 1)));
    memcpy(rows + width * (N - 1), value, sizeof(double) * (size_t)width);
}

/* Upper-triangular Hessian values in OSQP's CSC order; 1 if they differ from the loaded. */
static int hessian(int j0, const double *arrival) {
    double diagonal[N];
    for (int j = 0; j < N; ++j)
        diagonal[j] = (j > 0 ? LINK[j] : 0.0) + (j < N - 1 ? LINK[j + 1] : 0.0);
#if HARD
    for (int j = 0; j < N; ++j) VALUES[j] = HB[j][0] + diagonal[j];
    double warp = 0.0;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) warp += NULL_VECTOR[r] * arrival[r * 4 + c] * NULL_VECTOR[c];
    VALUES[j0] += warp;
    for (int j = 1; j < N; ++j) VALUES[N + j - 1] = -LINK[j];
#else
    for (int j = 0; j < N; ++j)
        for (int e = 0; e < 16; ++e)
            VALUES[j * 16 + e] = HB[j][e] + (e % 5 == 0 ? diagonal[j] : 0.0)
                                 + (j == j0 ? arrival[e] : 0.0);
    for (int j = 1; j < N; ++j)
        for (int a = 0; a < 4; ++a) VALUES[N * 16 + (j - 1) * 4 + a] = -LINK[j];
#endif
    int changed = K == 0;
    for (int i = 0; i < NNZ; ++i) {
        OSQPFloat value = (OSQPFloat)VALUES[ORDER[i]];
        if (value != PX[i]) changed = 1;
        PX[i] = value;
    }
    return changed;
}

/* One sample u[N_INPUTS] (non-finite entries: missing; the terms they feed are dropped) after the
   interval dt [s] (0 < dt < MAX_INTERVAL, else nothing is solved: the last estimate is held,
   status 0, flags 255). Returns OSQP's status (1 = solved); loads[4] keeps the previous
   estimate on failure; flags: the skipped updates and dropped model terms as in the KF
   (StepFlag; 255: interval rejected). */
int wheelload_mhe_step(const double *u, double dt, double *loads, int *iterations,
                       unsigned *flags) {
    double u0[N_INPUTS], valid[N_INPUTS], cost = COST;
    if (!(dt > 0.0 && dt < MAX_INTERVAL)) {
        memcpy(loads, HIST[N - 1], sizeof(double) * 4);
        *iterations = 0;
        *flags = 255u;
        return 0;
    }
    if (K == 0) {
        memset(ARRIVAL_FIRST, 0, sizeof ARRIVAL_FIRST);
        for (int r = 0; r < 4; ++r)
            ARRIVAL_FIRST[r * 5] = cost * LOAD_SCALE * LOAD_SCALE / (P0_VAR + Q_DENSITY * dt);
    }
    for (int i = 0; i < N_INPUTS; ++i) {
        valid[i] = isfinite(u[i]) ? 1.0 : 0.0;
        u0[i] = valid[i] != 0.0 ? u[i] : 0.0;
    }
    double h[W * W], g[W], link, xp[4], lo[W], hi[W], b[3], used[N_USED];
    const double *arg[SZ_ARG] = {u0, valid, &dt, HIST[N - 1], P_VECTOR, TUNING, &cost};
    double *res[SZ_RES] = {h, g, &link, xp, lo, hi, b, used};
    casadi_int iw[SZ_IW + 1];
    double w[SZ_W + 1];
    wheelload_mhe_terms(arg, res, iw, w, 0);
    *flags = 0;
    for (int i = 0; i < N_USED; ++i) *flags |= used[i] < 0.5 ? UPDATE_FLAGS[i] : 0u;
    if (K == 0) link = 0.0; /* the log's first sample: the arrival cost instead */
    double drift = 0.0;
#if HARD
    for (int r = 0; r < 4; ++r) drift += NULL_VECTOR[r] * (xp[r] - XP[N - 1][r]);
    drift *= link / LOAD_SCALE;
#endif
    shift(HB[0], h, W * W); shift(G[0], g, W); shift(LINK, &link, 1); shift(DRIFT, &drift, 1);
    shift(XP[0], xp, 4); shift(LO[0], lo, W); shift(HI[0], hi, W);
    int j0 = K < N - 1 ? (int)(N - 1 - K) : 0;
    const double *arrival = K <= N - 1 ? ARRIVAL_FIRST : ARRIVAL_STEADY;
    if (hessian(j0, arrival))
        osqp_update_data_mat(&wheelload_mhe_solver, PX, OSQP_NULL, NNZ, OSQP_NULL, OSQP_NULL, 0);
    const double *prior = HIST[0];
    for (int j = 0; j < N; ++j)
        for (int a = 0; a < W; ++a) {
            Q[j * W + a] = G[j][a];
            L[j * W + a] = fmax(LO[j][a], -OSQP_INFTY);
            U[j * W + a] = fmin(HI[j][a], OSQP_INFTY);
        }
#if HARD
    for (int j = 1; j < N; ++j) {
        Q[j] += DRIFT[j];
        Q[j - 1] -= DRIFT[j];
    }
    double nw = 0.0;
    for (int r = 0; r < 4; ++r) {
        double row = 0.0;
        for (int c = 0; c < 4; ++c) row += arrival[r * 4 + c] * (XP[j0][c] - prior[c]);
        nw += NULL_VECTOR[r] * row;
    }
    Q[j0] += nw / LOAD_SCALE;
#else
    for (int r = 0; r < 4; ++r) {
        double row = 0.0;
        for (int c = 0; c < 4; ++c) row += arrival[r * 4 + c] * prior[c];
        Q[j0 * W + r] -= row / LOAD_SCALE;
    }
#endif
    osqp_update_data_vec(&wheelload_mhe_solver, Q, HAS_Y ? L : OSQP_NULL, HAS_Y ? U : OSQP_NULL);
    memmove(XW, XW + W, sizeof(OSQPFloat) * (NX - W));
#if HAS_Y
    memmove(YW, YW + W, sizeof(OSQPFloat) * (NY - W));
    osqp_warm_start(&wheelload_mhe_solver, XW, YW);
#else
    osqp_warm_start(&wheelload_mhe_solver, XW, OSQP_NULL);
#endif
    osqp_solve(&wheelload_mhe_solver);
    int status = (int)wheelload_mhe_solver.info->status_val;
    *iterations = (int)wheelload_mhe_solver.info->iter;
    const OSQPFloat *x = wheelload_mhe_solver.solution->x;
    double out[4];
    if (status == 1) {
        memcpy(XW, x, sizeof XW);
#if HAS_Y
        memcpy(YW, wheelload_mhe_solver.solution->y, sizeof YW);
#endif
        const OSQPFloat *last = x + (N - 1) * W;
#if HARD
        double omega = fmin(fmax(last[0], LO[N - 1][0]), HI[N - 1][0]);
        for (int r = 0; r < 4; ++r) out[r] = XP[N - 1][r] + NULL_VECTOR[r] * omega * LOAD_SCALE;
#else
        for (int r = 0; r < 4; ++r) out[r] = last[r] * LOAD_SCALE;
#endif
        for (int r = 0; r < 4; ++r) out[r] = fmin(fmax(out[r], LOW_LOAD), HIGH_LOAD);
    } else {
        memcpy(out, HIST[N - 1], sizeof out);
    }
    shift(HIST[0], out, 4);
    memcpy(loads, out, sizeof out);
    ++K;
    return status;
}

/* A whole log (u: n x N_INPUTS, row-major; dt: the interval before each sample); wall time per
   sample in seconds. */
void wheelload_mhe_run(int n, const double *u, const double *dt, double *loads, int *status,
                       int *iterations, unsigned *flags, double *seconds) {
    wheelload_mhe_reset();
    for (int k = 0; k < n; ++k) {
        struct timespec start, stop;
        clock_gettime(CLOCK_MONOTONIC, &start);
        status[k] = wheelload_mhe_step(u + N_INPUTS * k, dt[k], loads + 4 * k, iterations + k,
                                       flags + k);
        clock_gettime(CLOCK_MONOTONIC, &stop);
        seconds[k] = (stop.tv_sec - start.tv_sec) + 1e-9 * (stop.tv_nsec - start.tv_nsec);
    }
}
"""


@dataclass(frozen=True)
class EmbeddedResult:
    loads: np.ndarray  # (n, 4) N
    status: np.ndarray  # (n,) OSQP status value
    flags: np.ndarray  # (n,) StepFlag bits of the skipped updates
    iterations: np.ndarray  # (n,)
    solve_time: np.ndarray  # (n,) s


class CompiledMhe:
    """The generated embedded MHE compiled to a shared library and loaded with ctypes."""

    def __init__(self, path: Path) -> None:
        self._lib = ctypes.CDLL(str(path))
        self._lib.wheelload_mhe_run.restype = None

    def run(self, signals: Signals) -> EmbeddedResult:
        u = np.ascontiguousarray(input_matrix(signals).T, dtype=float)
        dt = np.ascontiguousarray(sample_intervals(signals.t), dtype=float)
        n = len(signals)
        loads = np.zeros((n, 4))
        status = np.zeros(n, dtype=np.int32)
        iterations = np.zeros(n, dtype=np.int32)
        flags = np.zeros(n, dtype=np.uint32)
        seconds = np.zeros(n)

        def pointer(array, kind):
            return array.ctypes.data_as(ctypes.POINTER(kind))

        self._lib.wheelload_mhe_run(
            ctypes.c_int(n), pointer(u, ctypes.c_double), pointer(dt, ctypes.c_double),
            pointer(loads, ctypes.c_double),
            pointer(status, ctypes.c_int), pointer(iterations, ctypes.c_int),
            pointer(flags, ctypes.c_uint), pointer(seconds, ctypes.c_double),
        )  # fmt: skip
        return EmbeddedResult(loads, status, flags.astype(np.int64), iterations, seconds)


def build_mhe_library(
    vehicle: Vehicle, settings: MheSettings, folder: Path, dt: float
) -> CompiledMhe:
    """Generate, compile with gcc -O2 into ``folder/libwheelload_mhe.so`` and load."""
    folder = generate_mhe(vehicle, settings, Path(folder), dt)
    osqp_dir = folder / "osqp"
    sources = [
        folder / "wheelload_mhe.c",
        folder / f"{TERMS_NAME}.c",
        osqp_dir / "wheelload_mhe_workspace.c",
        *sorted((osqp_dir / "src").glob("*.c")),
    ]
    library = folder / "libwheelload_mhe.so"
    command = ["gcc", "-O2", "-shared", "-fPIC", "-std=gnu99", "-o", str(library),
               f"-I{osqp_dir}", f"-I{osqp_dir / 'inc' / 'public'}",
               f"-I{osqp_dir / 'inc' / 'private'}", f"-I{folder}",
               *map(str, sources), "-lm"]  # fmt: skip
    completed = subprocess.run(command, capture_output=True, text=True)
    if completed.returncode != 0:
        raise RuntimeError(f"compiling the embedded MHE failed:\n{completed.stderr[-3000:]}")
    return CompiledMhe(library)


MAIN = r"""
/* wheelload_mhe_main.c: run the embedded MHE over a text file of input rows.
   Each row: the interval dt [s] before the sample, then the ROW_SIZE - 1 inputs in
   wheelload.models.INPUTS order ('nan' = missing).
   Output CSV: fz_fl, fz_fr, fz_rl, fz_rr, status, iterations, flags; exit 2 on bad use. */
#include <stdio.h>
#include "osqp.h"

#ifndef ROW_SIZE
#error "ROW_SIZE (1 + number of inputs) must be defined"
#endif

void wheelload_mhe_reset(void);
int wheelload_mhe_step(const double *u, double dt, double *loads, int *iterations,
                       unsigned *flags);

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s INPUTS.txt ESTIMATES.csv\n", argv[0]);
        return 2;
    }
    FILE *in = fopen(argv[1], "r");
    if (!in) {
        fprintf(stderr, "%s: cannot open\n", argv[1]);
        return 2;
    }
    FILE *out = fopen(argv[2], "w");
    if (!out) {
        fprintf(stderr, "%s: cannot write\n", argv[2]);
        fclose(in);
        return 2;
    }
    fprintf(out, "fz_fl,fz_fr,fz_rl,fz_rr,status,iterations,flags,osqp_float_bytes\n");
    wheelload_mhe_reset();
    double row[ROW_SIZE], loads[4];
    for (;;) {
        int i;
        for (i = 0; i < ROW_SIZE; ++i)
            if (fscanf(in, "%lf", &row[i]) != 1) break;
        if (i < ROW_SIZE) break;
        int iterations;
        unsigned flags;
        int status = wheelload_mhe_step(row + 1, row[0], loads, &iterations, &flags);
        fprintf(out, "%.9g,%.9g,%.9g,%.9g,%d,%d,%u,%d\n", loads[0], loads[1], loads[2],
                loads[3], status, iterations, flags, (int)sizeof(OSQPFloat));
    }
    fclose(in);
    return fclose(out) == 0 ? 0 : 1;
}
"""


def mhe_sources(folder: Path) -> list[Path]:
    """The C files of a generated embedded MHE (without a main)."""
    osqp_dir = folder / "osqp"
    return [
        folder / "wheelload_mhe.c",
        folder / f"{TERMS_NAME}.c",
        osqp_dir / "wheelload_mhe_workspace.c",
        *sorted((osqp_dir / "src").glob("*.c")),
    ]


def mhe_includes(folder: Path) -> list[str]:
    osqp_dir = folder / "osqp"
    return [f"-I{osqp_dir}", f"-I{osqp_dir / 'inc' / 'public'}",
            f"-I{osqp_dir / 'inc' / 'private'}", f"-I{folder}"]  # fmt: skip


def build_mhe_program(
    vehicle: Vehicle,
    settings: MheSettings,
    folder: Path,
    dt: float,
    *,
    precision: Precision = Precision.DOUBLE,
    compiler: str = "gcc",
    flags: tuple[str, ...] = ("-O2",),
) -> Path:
    """Generate the embedded MHE and compile it with :data:`MAIN` into ``folder/wheelload_mhe``.

    ``compiler`` may be a cross compiler (e.g. ``arm-linux-gnueabihf-gcc`` with
    ``-static`` among ``flags``, run under ``qemu-arm``).
    """
    folder = generate_mhe(vehicle, settings, Path(folder), dt, precision)
    main = folder / "wheelload_mhe_main.c"
    main.write_text(f"#define ROW_SIZE {1 + len(INPUTS)}\n" + MAIN)
    binary = folder / "wheelload_mhe"
    command = [compiler, *flags, "-std=gnu99", "-o", str(binary), *mhe_includes(folder),
               str(main), *map(str, mhe_sources(folder)), "-lm"]  # fmt: skip
    completed = subprocess.run(command, capture_output=True, text=True)
    if completed.returncode != 0:
        raise RuntimeError(f"compiling the embedded MHE failed:\n{completed.stderr[-3000:]}")
    return binary


def write_inputs(signals: Signals, path: Path) -> Path:
    """The log's intervals and inputs as text rows for :data:`MAIN` (17 digits, 'nan' missing)."""
    rows = np.column_stack([sample_intervals(signals.t), input_matrix(signals).T])
    np.savetxt(path, rows, fmt="%.17g")
    return path
