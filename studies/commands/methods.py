"""``wheelload methods``: list the registered estimators with their paper reference."""

from __future__ import annotations

import argparse

from wheelload.estimators.registry import methods, tyre_methods
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits()


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("methods", help=CATALOG["methods"].summary)
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    table, tyres = methods(), tyre_methods()
    width = max(len(name) for name in (*table, *tyres))
    print("wheel normal loads F_z:")
    for name, info in table.items():
        marker = "*" if info.model_choice else " "
        print(f"{name:<{width}}{marker} {info.description}")
        print(f"{'':<{width}}  [{info.reference}]")
    print(
        "\n* on the KF's own vehicle model (suspension and equilibrium with the vehicle file's "
        "terms)\n  by default, so that a comparison ranks estimators, not models; "
        "--suspension paper on\n  `estimate` and `compare` gives the source paper's bare model."
    )
    print(
        "\ntyre forces F_x, F_y on the KF's F_z (from omega_*, torque_*, steer; tyre-rigid: none):"
    )
    for name, info in tyres.items():
        print(f"{name:<{width}}  {info.description}")
        print(f"{'':<{width}}  [{info.reference}]")
    print(
        "\n`estimate --method NAME` writes fx_*, fy_* beside fz_*; `study tyre-forces` scores "
        "them;\n`codegen --tyre-forces` emits tyre-forces' step as C beside the KF's."
    )
    return 0
