"""``wheelload codegen``: write an estimator as C.

``--estimator kf`` (default) writes the two-stage KF as a self-contained,
allocation-free C99 library; ``--estimator mhe`` writes the embedded MHE
(OSQP's generated solver, the generated QP-terms routine and the window
driver; see :mod:`wheelload.estimators.codegen.mhe`). Options that belong to
the other estimator are rejected with a message naming them.
"""

from __future__ import annotations

import argparse
import enum
from pathlib import Path

from wheelload.estimators import (
    Arrival,
    Constraint,
    Loss,
    Precision,
)
from wheelload.estimators.codegen.kf import CodegenOptions, ParamMode, generate
from wheelload.estimators.logs.output_files import check_output_folder
from wheelload.models import load_vehicle
from wheelload.studies.codegen_options import (
    BIAS_CHOICES,
    DEPRECATED_INTERVAL,
    INTERVAL_OPTION,
    interval,
    mhe_settings,
    own_options,
)
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import (
    CommandTraits,
    add_common_options,
    add_vehicle_option,
    vehicle_file,
)


class Estimator(enum.Enum):
    """The estimator to generate."""

    KF = "kf"
    MHE = "mhe"


#: Options of one estimator only, with their defaults (None on the parser, to see what was given).
KF_OPTIONS = {
    "params": ParamMode.RUNTIME.value,
    "prefix": "wheelload_kf",
    "tyre_forces": False,
    "fmu": False,
}
MHE_OPTIONS = {
    "horizon": 10,
    "constraint": Constraint.SOFT.value,
    "bounded": False,
    "suspension_loss": Loss.QUADRATIC.value,
    "constraint_loss": Loss.QUADRATIC.value,
    "huber_threshold": 2.0,
    "bias_states": "none",
    "lag": 0,
    "arrival": Arrival.KALMAN.value,
}


#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(vehicle=True, writes=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "codegen",
        help=CATALOG["codegen"].summary,
        description="kf: write PREFIX.h, PREFIX.c (the library, libm only), PREFIX_example.c "
        "(CSV log in, CSV estimates out; needs the v_* travel-rate columns), "
        "PREFIX_selftest.c, a Makefile and MISRA_DEVIATIONS.md. mhe: write the embedded MHE "
        "(OSQP's embedded solver in osqp/, wheelload_mhe_terms.c/.h, wheelload_mhe.c/.h, "
        "wheelload_mhe_state.h: one caller-owned state per instance; the fallback filter "
        "wheelload_mhe_kf.c/.h; wheelload_mhe_run.c, a whole log timed sample by sample "
        "(POSIX); the example wheelload_mhe_main.c, a Makefile and MISRA_DEVIATIONS.md).",
    )
    parser.add_argument(
        "--estimator",
        choices=[e.value for e in Estimator],
        default=Estimator.KF.value,
        help="kf: two-stage KF (default); mhe: moving-horizon estimator on OSQP",
    )
    add_vehicle_option(parser)
    parser.add_argument(
        "--out", required=True, metavar="DIR", help="folder: new or empty (created if missing)"
    )
    parser.add_argument(
        "--precision",
        choices=[p.value for p in Precision],
        default=Precision.DOUBLE.value,
        help="double (default) or float: kf: the whole library; mhe: OSQP's OSQPFloat",
    )
    parser.add_argument(
        INTERVAL_OPTION,
        type=float,
        metavar="SECONDS",
        help="the logger's nominal sample interval (default 0.01). kf: the default "
        "measurement noise (params sample_interval, settable) and the tyre step's "
        "discretisation; a step below it over interval_band is refused (INTERVAL_SHORT). "
        "mhe: the cost scale, the steady-state arrival weight and the linked filter's "
        "nominal interval",
    )
    for alias in DEPRECATED_INTERVAL:
        parser.add_argument(
            alias, type=float, dest=f"deprecated_{alias[2:].replace('-', '_')}",
            metavar="SECONDS", help=f"deprecated: use {INTERVAL_OPTION}",
        )  # fmt: skip
    kf = parser.add_argument_group("kf only")
    kf.add_argument(
        "--params",
        choices=[m.value for m in ParamMode],
        help="runtime (default): calibration in the parameter struct; baked: folded into the code",
    )
    kf.add_argument("--prefix", help="C symbol prefix (default wheelload_kf)")
    kf.add_argument(
        "--tyre-forces",
        action="store_const",
        const=True,
        help="also the tyre-force step (method tyre-forces: F_x, F_y per wheel with sigma on "
        "the KF's loads): PREFIX_tyre.h/.c; the example then reads omega_*, torque_*, steer "
        "and writes fx_*, fy_* and their sigma",
    )
    kf.add_argument(
        "--fmu",
        action="store_const",
        const=True,
        help="write OUT/PREFIX.fmu instead: a source FMU (FMI 3.0 co-simulation) of the "
        "combined F_x, F_y, F_z step (implies --tyre-forces; needs --params runtime), "
        "the parameters tunable, a fixed step of --interval",
    )
    mhe = parser.add_argument_group("mhe only")
    mhe.add_argument("--horizon", type=int, help="window length N (default 10)")
    mhe.add_argument(
        "--constraint",
        choices=[c.value for c in Constraint],
        help="equilibrium as a penalty (soft, default) or an equality (hard)",
    )
    mhe.add_argument("--bounded", action="store_const", const=True, help="bounds 0 <= Fz")
    losses = [loss.value for loss in Loss]
    mhe.add_argument("--suspension-loss", choices=losses, help="default quadratic")
    mhe.add_argument("--constraint-loss", choices=losses, help="default quadratic (soft only)")
    mhe.add_argument("--huber-threshold", type=float, help="Huber corner [sigma] (default 2)")
    mhe.add_argument("--bias-states", choices=list(BIAS_CHOICES), help="default none")
    mhe.add_argument("--lag", type=int, help="output the estimate of sample k - LAG (default 0)")
    mhe.add_argument(
        "--arrival",
        choices=[a.value for a in Arrival],
        help="kalman (default: the linked filter's covariance) or steady-state",
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    estimator = Estimator(args.estimator)
    vehicle_path = vehicle_file(args)
    check_output_folder(Path(args.out), [vehicle_path], force=args.force)
    if estimator is Estimator.MHE:
        return _run_mhe(args, vehicle_path)
    values = own_options(args, KF_OPTIONS, MHE_OPTIONS, estimator.value)
    options = CodegenOptions(
        precision=Precision(args.precision),
        params=ParamMode(values["params"]),
        prefix=values["prefix"],
        sample_interval=interval(args),
        tyre_forces=values["tyre_forces"],
    )
    if values["fmu"]:
        return _run_fmu(args, vehicle_path, options)
    library = generate(vehicle_path, args.out, options, allow_unusual=args.allow_unusual)
    for path in (library.header, library.source, *(library.tyre or ()), library.example,
                 library.selftest):  # fmt: skip
        print(path)
    print(
        f"{library.flops} arithmetic operations per step ({options.precision.value}, "
        f"{options.params.value} parameters); build with: make -C {args.out}"
    )
    return 0


def _run_fmu(args: argparse.Namespace, vehicle_path: Path, options: CodegenOptions) -> int:
    from wheelload.estimators.codegen.fmu import generate_fmu

    fmu = generate_fmu(vehicle_path, args.out, options, allow_unusual=args.allow_unusual,
                       force=args.force)  # fmt: skip
    print(fmu.path)
    print(
        f"source FMU (FMI 3.0 co-simulation, fixed step {fmu.interval} s, sources "
        f"{' '.join(fmu.sources)}); build with an importer's FMI 3.0 headers, e.g. "
        f"python3 -m fmpy compile {fmu.path}"
    )
    return 0


def _run_mhe(args: argparse.Namespace, vehicle_path: Path) -> int:
    from wheelload.estimators.codegen.mhe import embedded_settings, generate_mhe

    settings = mhe_settings(own_options(args, MHE_OPTIONS, KF_OPTIONS, Estimator.MHE.value))
    precision = Precision(args.precision)
    vehicle = load_vehicle(vehicle_path, allow_unusual=args.allow_unusual)
    dt = interval(args)
    folder = generate_mhe(
        vehicle, settings, Path(args.out), dt=dt, precision=precision,
        vehicle_path=vehicle_path, force=args.force,
    )  # fmt: skip
    realised = embedded_settings(settings, filter_linked=True, precision=precision)
    linked = "two-stage KF" if settings.constraint is Constraint.SOFT else "projection KF"
    print(
        f"written the embedded {realised.label()} "
        f"(dt = {dt} s, OSQP in {precision.value}, {linked} linked in) to {folder}"
    )
    return 0
