"""``wheelload methods``: list the registered estimators with their paper reference."""

from __future__ import annotations

import argparse

from wheelload.estimators.registry import methods


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "methods", help="list the estimators (names for --method / --methods)"
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    table = methods()
    width = max(len(name) for name in table)
    for name, info in table.items():
        print(f"{name:<{width}}  {info.description}")
        print(f"{'':<{width}}  [{info.reference}]")
    return 0
