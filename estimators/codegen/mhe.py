r"""Embedded MHE: OSQP's generated solver, the per-sample Functions and the window, in C.

The emitted folder holds

- ``osqp/``: OSQP's embedded code (``parameters="matrices"``) for the
  window's QP, set up by :class:`~wheelload.estimators.mhe.estimator.MovingHorizonEstimator`
  itself (its own workspace: the quadratic window's, or the extended window's of
  :mod:`wheelload.estimators.mhe.window` with its fixed Hessian pattern);
- ``wheelload_mhe_terms.c/.h``: the estimator's own per-sample CasADi
  Functions (:func:`~wheelload.estimators.mhe.terms.terms_function`, and for
  robust losses or bias states
  :func:`~wheelload.estimators.mhe.terms.residual_function`) as straight-line C
  from the KF's emitter (:func:`~wheelload.estimators.kernels.c_emitter.emit_statements`);
  their row weights come from the filter's noise Function
  (:mod:`wheelload.models.measurement_noise`, the vehicle file's input-dependent
  densities included, through the ``TUNING`` table), as in Python;
- ``wheelload_mhe_state.h``: the state of one instance (the driver's
  ``templates/mhe_plain_state.h`` or ``templates/mhe_window_state.h`` at the generated sizes);
- ``wheelload_mhe.c/.h``: the window driver (``templates/mhe_shared.c``, then
  ``templates/mhe_plain.c`` for quadratic losses, ``templates/mhe_window.c`` with
  auxiliary variables for
  the Huber/L1 losses and the bias states with their information
  recursion; the blocks both drivers share are spliced in from
  ``templates/mhe_blocks.c``), the lagged output, and the fallback filter;
- ``wheelload_mhe_run.c``: a whole log with each sample's wall time (``templates/mhe_run.c``,
  the runner of the Python binding; the only file that needs POSIX);
- ``wheelload_mhe_kf.c/.h`` (given the vehicle file): the fallback filter
  of the Python MHE as a ``wheelload codegen`` library linked in (soft
  constraint: the two-stage KF; hard: the projection KF with :math:`W =
  P^{-1}`, from :func:`~wheelload.estimators.kf.projection.projection_step_function`):
  the estimate of a sample whose QP is not solved (flagged ``fallback``), the
  Kalman arrival cost (:attr:`Arrival.KALMAN`) and the reported standard
  deviations.

The C is re-entrant: everything one estimator keeps between samples, its OSQP solver
included, is one caller-owned ``wheelload_mhe_state`` (``wheelload_mhe_state.h``; OSQP's
file-scope workspace is rewritten into a member of it by
:mod:`~wheelload.estimators.codegen.mhe_workspace`), so several instances run side by side
in one program. ``wheelload_mhe_reset(&state)`` starts a log;
``wheelload_mhe_step(&state, u, dt, &out)`` gives the loads of sample k - lag, the
KF's standard deviations, the equilibrium residual :math:`b - A x` of that
sample, the bias states (travel offsets [m], ax/ay [m/s²]), OSQP's status,
iterations, a fallback flag and the ``StepFlag`` bits. Input guarding: a
non-finite input is treated as missing, as in the KF: the rows that depend
on it are dropped and flagged. Every file is written through
:func:`~wheelload.estimators.logs.output_files.atomic_write`.

Limits, against the Python MHE:

- the cost scale (and the steady-state arrival weight) at the nominal
  interval given at generation; each sample's own interval sets its weights
  and random-walk link; a non-positive or non-finite interval holds the
  estimate (flags 255), as in Python;
- generated without the vehicle file (no filter linked): the arrival cost is
  the steady-state one, a sample whose QP is not solved keeps the previous
  estimate, a missing equilibrium input takes :math:`A x` of the previous MHE
  estimate (Python: of its filter's), and no standard deviations are reported
  (zeros).

Both windows load OSQP's Hessian values at the fixed pattern of the Python
MHE's workspace (OSQP's update of values and vectors, no dense matrix): the
quadratic window from its block-tridiagonal values, the extended window by
adding each sample's local terms at their positions in the pattern.

Precision: ``Precision.FLOAT`` generates OSQP with ``use_float``
(``OSQPFloat``; the program reports ``sizeof(OSQPFloat)``) and the linked KF
in float; the per-sample Functions and the window's assembly stay in
double. OSQP's float path cannot meet the default 1e-6 tolerance on the
extended window (at the iteration limit its solves end "solved
inaccurate", e.g. 447 of 1353 samples with an L1 equilibrium loss), so the
float build of that window runs at :data:`FLOAT_WINDOW_EPS` = 1e-5
(:func:`embedded_settings` says what a build realises); measured figures
are in ``tests/estimators/codegen/test_mhe_codegen_settings.py`` and
``tests/estimators/codegen/test_cross_compiled.py``. Compiling and running the generated
C: :mod:`~wheelload.estimators.codegen.mhe_build`.

Example
-------
>>> folder = generate_mhe(vehicle, MheSettings(horizon=20), Path("out"), dt=0.01,
...                       vehicle_path=Path("car.toml"))
"""

from __future__ import annotations

import dataclasses
import re
import shutil
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np

from wheelload.estimators.codegen.deviations import (
    LIBRARY_DEVIATIONS,
    MHE_DEVIATIONS,
    TRIVIAL_SIZE_DEVIATIONS,
    write_deviation_record,
)
from wheelload.estimators.codegen.kf import CodegenOptions, generate
from wheelload.estimators.codegen.mhe_workspace import make_reentrant
from wheelload.estimators.kernels.c_emitter import Precision, emit_statements
from wheelload.estimators.kf.projection import Weighting, projection_step_function
from wheelload.estimators.kf.tuning import TUNING
from wheelload.estimators.logs.output_files import atomic_write, check_output_folder
from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
from wheelload.estimators.mhe.qp import csc_value_order
from wheelload.estimators.mhe.quiet import quiet_stdout
from wheelload.estimators.mhe.settings import L1_CORE, Arrival, Constraint, Loss, MheSettings
from wheelload.estimators.mhe.terms import LOAD_SCALE, TERMS_NAME, terms_function
from wheelload.estimators.mhe.window import TRAVEL_UNIT
from wheelload.estimators.result import StepFlag
from wheelload.models import INPUTS, Vehicle, load_vehicle
from wheelload.models.input_validity import MAX_INTERVAL


def _array(name: str, values, kind: str = "double") -> str:
    flat = np.asarray(values, dtype=float if kind == "double" else int).ravel()
    if kind != "double":
        body = ", ".join(str(int(v)) for v in flat)
    else:
        body = ", ".join(repr(float(v)) if np.isfinite(v) else ("1e30" if v > 0 else "-1e30")
                         for v in flat)  # fmt: skip
    return f"static const {kind} {name}[{max(flat.size, 1)}] = {{{body or '0'}}};\n"


#: OSQP tolerance of the extended window in single precision: float32 cannot meet 1e-6 on
#: its residuals (solves end "solved inaccurate" at the iteration limit; measured on the plant
#: log with an L1 equilibrium loss: 447 of 1353 samples).
FLOAT_WINDOW_EPS = 1e-5


def embedded_settings(
    settings: MheSettings,
    *,
    filter_linked: bool = False,
    precision: Precision = Precision.DOUBLE,
) -> MheSettings:
    """The settings the embedded MHE realises (the Python MHE with these gives its numbers).

    With the fallback filter linked in (a vehicle file), the arrival cost as
    given; otherwise the steady-state one. In single precision the
    extended window's OSQP tolerances are at least :data:`FLOAT_WINDOW_EPS`.
    """
    if not filter_linked:
        settings = dataclasses.replace(settings, arrival=Arrival.STEADY_STATE)
    if precision is Precision.FLOAT and settings.extended:
        solver = settings.solver
        solver = dataclasses.replace(solver, eps_abs=max(solver.eps_abs, FLOAT_WINDOW_EPS),
                                     eps_rel=max(solver.eps_rel, FLOAT_WINDOW_EPS))  # fmt: skip
        settings = dataclasses.replace(settings, solver=solver)
    return settings


def generate_mhe(
    vehicle: Vehicle,
    settings: MheSettings,
    folder: Path,
    dt: float,
    precision: Precision = Precision.DOUBLE,
    *,
    vehicle_path: Path | None = None,
    force: bool = False,
) -> Path:
    """Write the embedded MHE's C sources to ``folder`` (see module docstring).

    With ``vehicle_path`` (the file ``vehicle`` was read from), the Python
    MHE's fallback filter generated from that file is linked in
    (``wheelload_mhe_kf.c``; soft: the two-stage KF, hard: the projection KF):
    the fallback, the Kalman arrival cost and the standard deviations.
    Without it the fallback holds the last estimate and the arrival cost is
    the steady-state one (:func:`embedded_settings`).

    ``precision`` is OSQP's floating type (``OSQPFloat``: the solver, its
    matrices and the QP vectors); the terms routine and the window stay in
    double. ``folder`` must be new or empty unless ``force``; the files are
    generated in a temporary folder inside it and each is renamed into place
    once complete (:func:`~wheelload.estimators.logs.output_files.atomic_write`), so
    an interrupted run leaves the old file or the new one, never a mix.
    """
    folder = Path(folder)
    check_output_folder(folder, [], force=force)
    folder.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".wheelload_mhe-", dir=folder))
    try:
        _generate_into(vehicle, settings, staging, dt, precision, vehicle_path)
        for source in sorted(p for p in staging.rglob("*") if p.is_file()):
            target = folder / source.relative_to(staging)
            target.parent.mkdir(parents=True, exist_ok=True)
            with atomic_write(target, replace=force) as temporary:
                shutil.copyfile(source, temporary)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return folder


def _generate_into(
    vehicle: Vehicle,
    settings: MheSettings,
    folder: Path,
    dt: float,
    precision: Precision,
    vehicle_path: Path | None,
) -> None:
    """Write every generated file into the (temporary) ``folder``."""
    linked = vehicle_path is not None
    settings = embedded_settings(settings, filter_linked=linked, precision=precision)
    if linked:
        hard = settings.constraint is Constraint.HARD
        _write_filter(vehicle, Path(vehicle_path), folder, precision, hard, dt)
    mhe = MovingHorizonEstimator(vehicle, settings)
    state = mhe.initial_state(dt)
    P0 = mhe.filter.initial_state().P
    if not np.allclose(P0, P0[0, 0] * np.eye(4), rtol=0, atol=0):
        raise ValueError("the embedded MHE needs an isotropic initial covariance")
    solver = mhe.window_qp.solver if settings.extended else mhe.workspace.solver
    with quiet_stdout():  # OSQP reports the files it writes
        solver.codegen(str(folder / "osqp"), prefix="wheelload_mhe_", parameters="matrices",
                       force_rewrite=True, use_float=precision is Precision.FLOAT)  # fmt: skip
    _undated(folder / "osqp" / "osqp_configure.h")
    make_reentrant(folder / "osqp")  # the solver a member of each instance's state
    low, high = mhe.load_bounds  # C has no infinite literal: OSQP takes 1e30 as infinite
    terms = terms_function(settings.constraint, null=mhe.null, pinv=mhe.pinv,
                           lower_load=max(low, -1e33), upper_load=min(high, 1e33))  # fmt: skip
    functions = [terms] + ([mhe.residuals] if settings.extended else [])
    _write_functions(functions, folder)
    n_bias = mhe.bias_report(np.zeros(mhe.beta_std.size)).size if settings.extended else 0
    (folder / "wheelload_mhe.h").write_text(HEADER.replace("@N_BIAS@", str(max(n_bias, 0)))
                                            .replace("@N_INPUTS@", str(len(INPUTS)))
                                            .replace("@LAG@", str(settings.lag)))  # fmt: skip
    sizes = _state_sizes(mhe, settings)
    (folder / "wheelload_mhe_state.h").write_text(_state_header(sizes, settings.extended, linked))
    aliases = "".join(f"#define {name} WHEELLOAD_MHE_{name}\n" for name in sizes)
    common = aliases + _common_defines(mhe, settings, state, dt, float(P0[0, 0]))
    kalman = settings.arrival is Arrival.KALMAN
    common = common.replace("#define KALMAN_ARRIVAL 0", f"#define KALMAN_ARRIVAL {int(kalman)}")
    if settings.extended:
        specific, template = _window_defines(mhe, settings), "mhe_window.c"
    else:
        specific, template = _plain_defines(mhe, settings), "mhe_plain.c"
    driver = spliced(template)
    fallback = (TEMPLATES / ("mhe_kf.c" if linked else "mhe_hold.c")).read_text()
    tail = (TEMPLATES / "mhe_tail.c").read_text()
    shared = (TEMPLATES / "mhe_shared.c").read_text()
    source = PRELUDE + common + specific + shared + driver + fallback + tail
    (folder / "wheelload_mhe.c").write_text(source)
    (folder / RUNNER).write_text((TEMPLATES / "mhe_run.c").read_text())
    (folder / EXAMPLE).write_text((TEMPLATES / "mhe_main.c").read_text())
    (folder / "Makefile").write_text(_makefile(folder))
    filter_deviations = [d.for_prefix(FILTER_PREFIX) for d in LIBRARY_DEVIATIONS] if linked else []
    qp = mhe.window_qp if settings.extended else None
    trivial = mhe.hard or (qp is not None and qp.n_bias > 0 and not qp.travel_bias)
    sizes = TRIVIAL_SIZE_DEVIATIONS if trivial else ()
    write_deviation_record(folder, [*filter_deviations, *MHE_DEVIATIONS, *sizes], "wheelload_mhe")


def _undated(path: Path) -> None:
    """Drop the date from OSQP's "autogenerated by OSQP on <date>" line: the same window
    gives the same files (a reproducible build, compiled once by ``cached_object``)."""
    text = path.read_text()
    path.write_text(re.sub(r"(autogenerated by OSQP) on [^\n]*", r"\1", text, count=1))


def mhe_sources(folder: Path) -> list[Path]:
    """The C files of a generated embedded MHE (without a main)."""
    osqp_dir = folder / "osqp"
    linked = [folder / f"{FILTER_PREFIX}.c"] if (folder / f"{FILTER_PREFIX}.c").exists() else []
    return [
        folder / "wheelload_mhe.c",
        folder / RUNNER,
        folder / f"{TERMS_NAME}.c",
        *linked,
        osqp_dir / "wheelload_mhe_workspace.c",
        *sorted((osqp_dir / "src").glob("*.c")),
    ]


def include_directories(folder: Path) -> list[Path]:
    """The folders of a generated embedded MHE's headers, in ``-I`` order."""
    osqp_dir = folder / "osqp"
    return [osqp_dir, osqp_dir / "inc" / "public", osqp_dir / "inc" / "private", folder]


def mhe_includes(folder: Path) -> list[str]:
    """The include flags of a generated embedded MHE's sources."""
    return [f"-I{directory}" for directory in include_directories(folder)]


def relative_includes(folder: Path) -> list[str]:
    """:func:`mhe_includes` relative to ``folder`` (for a build run inside it)."""
    return [f"-I{directory.relative_to(folder)}" for directory in include_directories(folder)]


def _makefile(folder: Path) -> str:
    """A Makefile building the folder's sources into ``libwheelload_mhe.a`` (paths relative
    to the folder, so it builds wherever the folder is moved)."""
    sources = " \\\n    ".join(str(p.relative_to(folder)) for p in mhe_sources(folder))
    includes = " ".join(relative_includes(folder))
    makefile = MAKEFILE.replace("@SOURCES@", sources).replace("@INCLUDES@", includes)
    return makefile.replace("@EXAMPLE@", EXAMPLE)


#: The example program's source in the generated folder (``templates/mhe_main.c``).
EXAMPLE = "wheelload_mhe_main.c"
#: The timed whole-log runner (``wheelload_mhe_run``, ``templates/mhe_run.c``), apart from the
#: estimator: it alone needs POSIX (clock_gettime).
RUNNER = "wheelload_mhe_run.c"

#: The embedded MHE's Makefile: ``make`` gives the static library and the example program,
#: ``make CC=...`` a cross build (make's built-in default cc does not count: gcc unless CC is
#: given, on the command line or in the environment).
MAKEFILE = """# Generated by wheelload: the embedded MHE as a static library, and its example.
#     make                       libwheelload_mhe.a and wheelload_mhe (gcc)
#     make CC=arm-none-eabi-gcc  a cross build (CC=... make likewise); CFLAGS likewise
#     make libwheelload_mhe.a    the library alone (a target without a C library to link)
# Link a program with libwheelload_mhe.a -lm and include wheelload_mhe.h; each estimator is
# one wheelload_mhe_state of the program's (wheelload_mhe_main.c runs one per log).
ifeq ($(origin CC),default)
CC = gcc
endif
CFLAGS ?= -O2 -std=gnu99
INCLUDES = @INCLUDES@
SOURCES = @SOURCES@
OBJECTS = $(SOURCES:.c=.o)

all: libwheelload_mhe.a wheelload_mhe

libwheelload_mhe.a: $(OBJECTS)
	$(AR) rcs $@ $(OBJECTS)

wheelload_mhe: @EXAMPLE@ libwheelload_mhe.a
	$(CC) $(CFLAGS) $(INCLUDES) -o $@ @EXAMPLE@ libwheelload_mhe.a -lm

%.o: %.c
	$(CC) $(CFLAGS) $(INCLUDES) -c -o $@ $<

clean:
	rm -f $(OBJECTS) libwheelload_mhe.a wheelload_mhe

.PHONY: all clean
"""


TEMPLATES = Path(__file__).with_name("templates")
#: The blocks both window drivers share (``@@ NAME`` lines, see :func:`spliced`)
BLOCKS = "mhe_blocks.c"


def spliced(template: str) -> str:
    """The window driver ``template`` with each ``@@ NAME`` line replaced by that block.

    The blocks are those of :data:`BLOCKS`: each runs from its ``@@ NAME`` line to the
    next (the file's opening comment, before the first, is not emitted).
    """
    _, *parts = (TEMPLATES / BLOCKS).read_text().split("\n@@ ")
    blocks = {}
    for part in parts:
        name, _, body = part.partition("\n")
        blocks[f"@@ {name}\n"] = body if body.endswith("\n") else body + "\n"
    lines = (TEMPLATES / template).read_text().splitlines(keepends=True)
    return "".join(blocks[line] if line.startswith("@@ ") else line for line in lines)


FILTER_PREFIX = "wheelload_mhe_kf"


def _write_filter(
    vehicle: Vehicle,
    vehicle_path: Path,
    folder: Path,
    precision: Precision,
    hard: bool,
    dt: float,
) -> None:
    """The MHE's fallback filter for ``vehicle_path`` as ``wheelload_mhe_kf.c/.h`` in ``folder``.

    Its nominal interval (params ``sample_interval``) is the MHE's ``dt``. Soft
    constraint: the two-stage KF library; hard: the same library around the
    projection KF's step (:math:`W = P^{-1}`), as the Python MHE's ``filter``.
    """
    if load_vehicle(vehicle_path, allow_unusual=True) != vehicle:
        raise ValueError(
            f"{vehicle_path}: is not the vehicle the MHE is generated for: give the file it "
            "was read from"
        )
    with tempfile.TemporaryDirectory(dir=folder) as scratch:
        # Its nominal interval the MHE's: a step below it over interval_band is refused.
        options = CodegenOptions(precision=precision, prefix=FILTER_PREFIX, sample_interval=dt)
        step = projection_step_function(Weighting.MAXIMUM_PROBABILITY) if hard else None
        library = generate(vehicle_path, Path(scratch), options, step, allow_unusual=True)
        for path in (library.header, library.source):
            shutil.copyfile(path, folder / path.name)


def _write_functions(functions: list[ca.Function], folder: Path) -> None:
    """``wheelload_mhe_terms.c/.h``: each SX Function as one straight-line C function.

    ``void NAME(const double *in0, ..., double *out0, ...)``, one pointer per
    input and output of the Function (dense, column-major), emitted by
    :func:`~wheelload.estimators.kernels.c_emitter.emit_statements` (as the KF's C).
    """
    header = ["/* generated by wheelload: the MHE's per-sample Functions (double). */",
              "#ifndef WHEELLOAD_MHE_TERMS_H", "#define WHEELLOAD_MHE_TERMS_H"]  # fmt: skip
    source = ["/* generated by wheelload from the CasADi Functions of wheelload.estimators."
              "mhe.terms */", "#include <math.h>", f'#include "{TERMS_NAME}.h"']  # fmt: skip
    for f in functions:
        ins = [f"const double *{f.name_in(i)}" for i in range(f.n_in())]
        outs = [f"double *{f.name_out(i)}" for i in range(f.n_out())]
        signature = f"void {f.name()}({', '.join(ins + outs)})"
        header += [f"/* {f} */", signature + ";"]
        body = emit_statements(
            f, [f"{f.name_in(i)}[{{}}]" for i in range(f.n_in())],
            [f"{f.name_out(i)}[{{}}]" for i in range(f.n_out())], Precision.DOUBLE, "double",
        )  # fmt: skip
        unused = [
            f"(void){f.name_in(i)};" for i in range(f.n_in()) if f"{f.name_in(i)}[" not in body
        ]
        lines = unused + body.splitlines()
        source += ["", signature + " {", *("    " + line for line in lines), "}"]
    header.append("#endif")
    (folder / f"{TERMS_NAME}.h").write_text("\n".join(header) + "\n")
    (folder / f"{TERMS_NAME}.c").write_text("\n".join(source) + "\n")


def _common_defines(mhe, settings: MheSettings, state, dt: float, p0: float) -> str:
    """Sizes, scales and tables both drivers use."""
    low, high = mhe.load_bounds
    x0 = np.array(mhe.filter.parameters.static(), dtype=float)
    return "".join([
        f"#define HARD {int(mhe.hard)}\n",
        f"#define LAG {settings.lag}\n#define NP {mhe.p.size}\n#define KALMAN_ARRIVAL 0\n",
        # the window sample of the output (sample k - LAG): N - 1 - LAG
        f"#define OUTPUT_SAMPLE {settings.horizon - 1 - settings.lag}\n",
        f"#define LOAD_SCALE {LOAD_SCALE!r}\n#define DT {float(dt)!r}\n",
        f"#define Q_DENSITY {mhe.process_noise_density!r}\n",
        f"#define P0_VAR {p0!r}\n",
        f"#define MAX_INTERVAL {float(MAX_INTERVAL)!r}\n",
        # A step below DT / INTERVAL_BAND is refused (the guard setting interval_band of the
        # linked filter): the cost scale, arrival weight and filter are DT's.
        f"#define INTERVAL_BAND {float(TUNING.value(mhe.tuning, 'interval_band'))!r}\n",
        f"#define INTERVAL_SHORT {int(StepFlag.INTERVAL_SHORT)}u\n",
        f"#define COST {float(state.cost)!r}\n#define RHO0 {float(settings.solver.rho)!r}\n",
        f"#define EPS_ABS {float(settings.solver.eps_abs)!r}\n",
        f"#define EPS_REL {float(settings.solver.eps_rel)!r}\n",
        f"#define LOW_LOAD {float(max(low, -1e30))!r}\n",
        f"#define HIGH_LOAD {float(min(high, 1e30))!r}\n",
        f"#define LOAD_LIMIT {float(mhe.load_limit)!r}\n",
        f"#define DIFFUSE_VARIANCE {float(mhe.diffuse_variance)!r}\n",
        f"#define N_INPUTS {len(INPUTS)}\n#define N_USED {len(StepFlag.update_flags())}\n",
        "static const unsigned UPDATE_FLAGS[N_USED] = {"
        + ", ".join(f"{flag.value}u" for flag in StepFlag.update_flags())
        + "};\n",
        _array("ARRIVAL_STEADY", state.steady),
        _array("P_VECTOR", mhe.p),
        _array("TUNING", mhe.tuning),
        _array("NULL_VECTOR", mhe.null) if mhe.hard else "",
        _array("A_MATRIX", mhe.A),
        _array("X0", x0),
    ])  # fmt: skip


def _state_sizes(mhe, settings: MheSettings) -> dict[str, int]:
    """The sizes of the state's arrays (``WHEELLOAD_MHE_<name>`` in wheelload_mhe_state.h;
    the driver's ``<name>``): horizon N, load variables W per sample, and per driver its own."""
    N, width = settings.horizon, mhe.width
    if not settings.extended:  # the quadratic window: block-tridiagonal Hessian
        rows = N * width if settings.bounded else 0
        nnz = csc_value_order(N, width).size
        return dict(N=N, W=width, NX=N * width, NY=max(rows, 1), NNZ=nnz,
                    NV=N * width * width + (N - 1) * width)  # fmt: skip
    qp = mhe.window_qp
    nb = qp.n_bias
    return dict(N=N, W=width, WIDTH=qp.width, NB=nb, NK=max(nb, 1), NL=qp.width + nb,
                NQ=N * qp.width + nb, NNZ=qp.order.size)  # fmt: skip


def _state_header(sizes: dict[str, int], extended: bool, linked: bool) -> str:
    """wheelload_mhe_state.h: the sizes and the state struct of the driver."""
    template = "mhe_window_state.h" if extended else "mhe_plain_state.h"
    member = "    wheelload_mhe_kf_state kf;               /* the fallback filter's state */\n"
    member = member if linked else ""
    body = (TEMPLATES / template).read_text().replace("@KF_MEMBER@\n", member)
    defines = "".join(f"#define WHEELLOAD_MHE_{name} {value}\n" for name, value in sizes.items())
    include = f'#include "{FILTER_PREFIX}.h"\n' if linked else ""
    return STATE_HEADER.format(defines=defines, body=body, include=include)


def _plain_defines(mhe, settings: MheSettings) -> str:
    """The quadratic window's layout: block-tridiagonal Hessian in OSQP's CSC order."""
    rows = settings.horizon * mhe.width if settings.bounded else 0
    order = csc_value_order(settings.horizon, mhe.width)
    return "".join([f"#define HAS_Y {int(rows > 0)}\n", _array("ORDER", order, "int")])


def _window_defines(mhe, settings: MheSettings) -> str:
    """The extended window's layout, losses and bias states (:mod:`.mhe.window`).

    The pattern is the one the Python MHE's OSQP workspace was set up with, in CSC form:
    ``COLUMN_START[c]`` is the first of column ``c``'s values, ``ROW_INDEX[i]`` the row of
    the ``i``-th (ascending within a column).
    """
    qp = mhe.window_qp
    rows, cols = qp.rows[qp.order], qp.cols[qp.order]
    if np.any(np.diff(cols * qp.n + rows) <= 0):
        raise RuntimeError("the window's Hessian values are not in CSC order")
    column_start = np.searchsorted(cols, np.arange(qp.n + 1))
    nd = qp.travel_basis.shape[1] if qp.travel_bias else 0
    # the acceleration biases: ax and ay, or ay alone (one column)
    columns = [0, 1] if qp.n_bias - nd == 2 else [1]

    def loss(group, name):
        kappa, mu = group.weights() if group.robust else (1.0, 0.0)
        corner = group.threshold if group.kind is Loss.HUBER else L1_CORE
        scale = 1.0 if group.kind is Loss.HUBER else 1.0 / L1_CORE
        return (f"#define {name}_ROBUST {int(group.robust)}\n#define KAPPA_{name[0]} {kappa!r}\n"
                f"#define MU_{name[0]} {float(mu)!r}\n#define CORNER_{name[0]} {corner!r}\n"
                f"#define SCALE_{name[0]} {scale!r}\n")  # fmt: skip

    return "".join([
        f"#define NS {qp.ns}\n#define NC {qp.nc}\n#define ND {nd}\n",
        f"#define TRAVEL_UNIT {TRAVEL_UNIT!r}\n",
        loss(settings.suspension_loss, "SUSPENSION"),
        loss(settings.constraint_loss, "CONSTRAINT"),
        _array("COLUMN_START", column_start, "int"),
        _array("ROW_INDEX", rows, "int"),
        _array("PINV", mhe.pinv) if mhe.hard and qp.n_bias > nd else "",
        _array("TRAVEL_BASIS", qp.travel_basis) if nd else "",
        _array("ACC_COLS", columns, "int") if qp.n_bias > nd else "",
        _array("BETA_BOUND", mhe.beta_bound),
        _array("BETA_DENSITY", mhe.beta_density) if qp.n_bias else "",
        _array("BETA_INFO0", 1.0 / mhe.beta_std**2),
    ])  # fmt: skip


PRELUDE = """/* wheelload_mhe.c: generated by wheelload (wheelload.estimators.codegen.mhe). */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <string.h>
#include "osqp.h"
#include "wheelload_mhe_workspace.h"
#include "wheelload_mhe_terms.h"
#include "wheelload_mhe.h"
"""


HEADER = r"""/* wheelload_mhe.h: the embedded moving-horizon wheel-load estimator (generated).
 *
 * Re-entrant: all that one estimator keeps from sample to sample, its OSQP solver included, is
 * one wheelload_mhe_state the caller owns (static, on the stack or from an allocator); several
 * instances (vehicles, logs) run side by side in one program, interleaved as the caller likes.
 * Nothing is global and nothing is allocated; one instance is used by one thread at a time.
 *
 *     static wheelload_mhe_state front_axle, rear_axle;  // sizeof: wheelload_mhe_state_size()
 *     wheelload_mhe_output out;
 *     wheelload_mhe_reset(&front_axle);
 *     wheelload_mhe_reset(&rear_axle);
 *     for (;;) { ... wheelload_mhe_step(&front_axle, u, dt, &out); ... }
 *
 * The state holds pointers into itself (its solver's): it is reset where it lives, never copied
 * or moved between samples (a step on a copy is refused: WHEELLOAD_MHE_NOT_RESET). */
#ifndef WHEELLOAD_MHE_H
#define WHEELLOAD_MHE_H

#include <stddef.h>

#include "wheelload_mhe_state.h"

#define WHEELLOAD_MHE_N_INPUTS @N_INPUTS@ /* wheelload.models.INPUTS order */
#define WHEELLOAD_MHE_N_BIAS @N_BIAS@     /* entries of bias in use */
#define WHEELLOAD_MHE_LAG @LAG@           /* samples: loads are the estimate of sample k - LAG */
/* wheelload_mhe_step's status for a state not reset where it is (never reset, or copied or
   moved since): nothing is estimated, out zeroed with flags 255; reset it. */
#define WHEELLOAD_MHE_NOT_RESET (-1)

typedef struct {
    double loads[4];    /* wheel loads [N] of sample k - LAG */
    double std[4];      /* the fallback filter's standard deviations [N] (0: no filter) */
    double residual[3]; /* b - A x of that sample: vertical [N], pitch, roll [N m] */
    double bias[6];     /* bias states: travel offsets FL..RR [m] and/or ax, ay [m/s^2] */
    int iterations;     /* ADMM iterations */
    int fallback;       /* 1: the QP was not solved or its loads out of bounds: the filter's */
    unsigned flags;     /* skipped updates and dropped terms (StepFlag); 255: interval rejected,
                           with StepFlag INTERVAL_SHORT (1 << 29) when below DT / interval_band */
} wheelload_mhe_output;

/* Start a new log in state: its solver set up afresh, inert window, static loads. */
void wheelload_mhe_reset(wheelload_mhe_state *state);

/* One sample u[WHEELLOAD_MHE_N_INPUTS] (non-finite entries: missing; the terms they feed are
   dropped) after the interval dt [s] (0 < dt < the maximum interval, else nothing is solved:
   the last estimate is held, status 0, flags 255; so too below the generated interval DT over
   the filter's interval_band, the log faster than the MHE was generated for: flags
   255 | INTERVAL_SHORT, regenerate with --interval). Returns OSQP's status (1 = solved), or
   WHEELLOAD_MHE_NOT_RESET. */
int wheelload_mhe_step(wheelload_mhe_state *state, const double *u, double dt,
                       wheelload_mhe_output *out);

/* sizeof(wheelload_mhe_state), for a caller that allocates it by size (e.g. through an FFI). */
size_t wheelload_mhe_state_size(void);

/* A whole log of n samples in state, reset first (u: n x WHEELLOAD_MHE_N_INPUTS row-major; dt:
   the interval before each sample); per sample its outputs and wall time [s]. */
void wheelload_mhe_run(wheelload_mhe_state *state, int n, const double *u, const double *dt,
                       double *loads, double *std, double *residual, double *bias, int *status,
                       int *iterations, int *fallback, unsigned *flags, double *seconds);

#endif
"""

STATE_HEADER = """/* wheelload_mhe_state.h: the state of one embedded MHE instance (generated by
 * wheelload; see wheelload_mhe.h). Its members are the estimator's: the caller owns the struct
 * and passes it to wheelload_mhe_reset and wheelload_mhe_step, and reads or writes none of
 * them. The sizes are fixed at generation. */
#ifndef WHEELLOAD_MHE_STATE_H
#define WHEELLOAD_MHE_STATE_H

#include "wheelload_mhe_workspace.h"
{include}
{defines}
{body}
#endif
"""
