"""``wheelload bench WHAT``: timings, printed, never asserted.

Each benchmark is registered by its module's ``register_bench(subparsers)``
(:data:`~wheelload.studies.commands.bench.BENCHMARKS`), on first use of its parser:
``wheelload bench --help`` lists them from the table, and ``wheelload bench WHAT``
imports WHAT's module only.
"""

from __future__ import annotations

import argparse
import importlib

from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.bench import BENCHMARKS
from wheelload.studies.commands.options import CommandTraits, add_message_options

#: The bench command itself only dispatches: each benchmark has its own options.
TRAITS = CommandTraits()


class DeferredParser(argparse.ArgumentParser):
    """A benchmark's parser, its arguments added by its module (``module``) when it first
    parses or prints its help, or when :meth:`build_arguments` is called."""

    def __init__(self, *, benchmark: str, module: str, **kwargs) -> None:
        super().__init__(**kwargs)
        self.benchmark, self.module = benchmark, module
        self.built = False

    def build_arguments(self) -> None:
        """Import the module and let its ``register_bench`` add the arguments (once)."""
        if not self.built:
            self.built = True
            importlib.import_module(self.module).register_bench(_Into(self.benchmark, self))
            add_message_options(self)

    def parse_known_args(self, args=None, namespace=None):
        self.build_arguments()
        return super().parse_known_args(args, namespace)

    def format_help(self) -> str:
        self.build_arguments()
        return super().format_help()

    def format_usage(self) -> str:
        self.build_arguments()
        return super().format_usage()


class _Into:
    """What ``register_bench`` is handed instead of the sub-parsers: its ``add_parser``
    returns the deferred parser itself (its summary is the table's, listed already)."""

    def __init__(self, name: str, parser: DeferredParser) -> None:
        self.name, self.parser = name, parser

    def add_parser(self, name: str, *, description: str | None = None):
        if name != self.name:
            raise ValueError(f"{self.parser.module} registers bench {name}, not {self.name}")
        self.parser.description = description
        return self.parser


def register(subparsers: argparse._SubParsersAction) -> None:
    bench = subparsers.add_parser("bench", help=CATALOG["bench"].summary)
    benchmarks = bench.add_subparsers(
        dest="what", required=True, metavar="WHAT", parser_class=DeferredParser
    )
    for name, benchmark in BENCHMARKS.items():
        benchmarks.add_parser(name, help=benchmark.summary, benchmark=name, module=benchmark.module)
    add_message_options(bench)
    bench.set_defaults(traits=TRAITS)
