"""``wheelload codegen``: write the two-stage KF as a self-contained C99 library."""

from __future__ import annotations

import argparse

from wheelload.estimators.c_emitter import Precision
from wheelload.estimators.codegen import CodegenOptions, ParamMode, generate


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "codegen",
        help="generate the two-stage KF as an allocation-free C99 library",
        description="Write PREFIX.h, PREFIX.c (the library, libm only), PREFIX_example.c "
        "(CSV log in, CSV estimates out; needs the v_* travel-rate columns), "
        "PREFIX_selftest.c and a Makefile.",
    )
    parser.add_argument("--vehicle", required=True, help="vehicle TOML file")
    parser.add_argument("--out", required=True, help="output folder (created if missing)")
    parser.add_argument(
        "--precision", choices=[p.value for p in Precision], default=Precision.DOUBLE.value
    )
    parser.add_argument(
        "--params",
        choices=[m.value for m in ParamMode],
        default=ParamMode.RUNTIME.value,
        help="runtime: calibration in the parameter struct; baked: folded into the code",
    )
    parser.add_argument("--prefix", default="wheelload_kf", help="C symbol prefix")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    options = CodegenOptions(
        precision=Precision(args.precision), params=ParamMode(args.params), prefix=args.prefix
    )
    library = generate(args.vehicle, args.out, options)
    for path in (library.header, library.source, library.example, library.selftest):
        print(path)
    print(
        f"{library.flops} arithmetic operations per step ({options.precision.value}, "
        f"{options.params.value} parameters); build with: make -C {args.out}"
    )
    return 0
