"""``wheelload docs``: build the documentation site (pages, API reference, executed journeys)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options

DOCS_PACKAGES = ("sphinx", "furo", "myst_parser")


#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(writes=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "docs",
        help=CATALOG["docs"].summary,
        description="Build the documentation site with warnings as errors. The journeys' "
        "commands run while it builds (a few minutes). Needs the docs extra: "
        "pip install -e '.[docs]'.",
    )
    parser.add_argument(
        "--out", required=True, metavar="DIR", help="folder of the site (absent or empty)"
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=min(4, os.cpu_count() or 1),
        help="pages read in parallel (default: the cores, at most 4)",
    )
    parser.add_argument(
        "--mathjax",
        help="a MathJax tex-svg.js to serve with the site (default: the one of the "
        "sphinx-mathjax-offline package, in the docs extra); the pages need no network",
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import importlib.util

    missing = [name for name in DOCS_PACKAGES if importlib.util.find_spec(name) is None]
    if missing:
        raise ValueError(
            f"the docs need {', '.join(missing)}: install them with pip install -e '.[docs]'"
        )
    if args.jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {args.jobs}")
    from wheelload.studies.docs import build_docs

    index = build_docs(
        Path(args.out),
        force=args.force,
        jobs=args.jobs,
        mathjax=Path(args.mathjax) if args.mathjax else None,
    )
    print(f"wrote the site: {index}")
    return 0
