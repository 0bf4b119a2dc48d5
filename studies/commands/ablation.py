"""``wheelload ablation``: each model term on and off, both bundled vehicles, every scenario.

The study is :mod:`~wheelload.studies.experiments.model_terms_ablation`.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from wheelload.models.runtime.temporaries import replacing
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options, show_progress
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenarios import SCENARIOS
from wheelload.studies.experiments import model_terms_ablation

logger = logging.getLogger(__name__)

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(vehicle=True, writes=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "ablation",
        help=CATALOG["ablation"].summary,
        description=__doc__.splitlines()[0],
    )
    parser.add_argument(
        "--vehicle", action="append", help="vehicle file (repeatable; default: both bundled)"
    )
    parser.add_argument(
        "--scenario", action="append", choices=sorted(SCENARIOS), metavar="NAME",
        help="scenario (repeatable; default: all ten)",
    )  # fmt: skip
    parser.add_argument("--seed", type=int, default=0, help="random seed (sensor noise)")
    parser.add_argument("--noise", type=float, default=1.0, help="sensor noise scale")
    parser.add_argument(
        "--quick", action="store_true", help="laps cut to 10 %% of their length (tests)"
    )
    parser.add_argument("--out", metavar="FILE", help="file: also write the long table as CSV")
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    out = Path(args.out) if args.out else None
    if out is not None and out.exists() and not args.force:
        raise ValueError(f"{out} exists: choose another --out or add --force")
    paths = (
        [Path(p) for p in args.vehicle] if args.vehicle else model_terms_ablation.bundled_vehicles()
    )
    scenarios = args.scenario or list(SCENARIOS)
    options = Options(seed=args.seed, shorten=0.1 if args.quick else 1.0)
    table = model_terms_ablation.ablation(
        paths, scenarios, options, noise=args.noise,
        progress=(lambda text: print(text, file=sys.stderr, flush=True))
        if show_progress(args) else logger.info,
        allow_unusual=args.allow_unusual,
    )  # fmt: skip
    for vehicle in dict.fromkeys(table["vehicle"]):
        for title, labels in model_terms_ablation.label_groups().items():
            print(f"\n{vehicle}: pooled RMSE / Max [N], {title}")
            print(model_terms_ablation.wide_table(table, vehicle, labels).to_string())
    if out is not None:
        with replacing(out) as temporary:
            table.to_csv(temporary, index=False, float_format="%.1f")
        print(f"\nwrote {out}")
    return 0
