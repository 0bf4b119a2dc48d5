"""``wheelload compare LOG --vehicle FILE --methods A,B,...``: the paper-style error table.

Runs each registered method on the log (the family methods on the KF's own
vehicle model unless ``--suspension paper``), prints RMSE, RMSE %, P95 and Max per
wheel and pooled (Siegloff & Choi eq. 26-34) and the time per sample, and
with ``--figures DIR`` writes one figure per wheel of every estimate against
the reference.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.estimators import SuspensionModel
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import (
    CommandTraits,
    add_common_options,
    add_suspension_option,
    check_logs_exist,
    log_of,
    vehicle_of,
)

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(log=True, scores=True, vehicle=True, writes=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "compare",
        help=CATALOG["compare"].summary,
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("log", help="log file (.csv or .parquet) with fz_fl..fz_rr reference")
    parser.add_argument("--vehicle", required=True, metavar="FILE", help="vehicle TOML file")
    parser.add_argument(
        "--methods",
        default="kf,B,C,D,E,E+C,F",
        help="comma-separated method names (see `wheelload methods`; default kf,B,C,D,E,E+C,F)",
    )
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per method (default 3)")
    parser.add_argument(
        "--figures",
        metavar="DIR",
        help="folder (created if missing) for one PNG per wheel: LOGNAME_compare_fl.png ..",
    )
    parser.add_argument(
        "--csv", metavar="FILE", help="write the table (one row per method and wheel) to this CSV"
    )
    add_suspension_option(parser)
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    # imported to run, not for --help (studies/commands/__init__.py)
    from wheelload.studies.pipeline.comparison import (
        compare_methods,
        format_table,
        long_table,
        parse_methods,
    )
    from wheelload.studies.plots.comparison import (
        check_writable,
        figure_paths,
        plot_comparison,
        write_csv,
    )

    names = parse_methods(args.methods)
    log_path = Path(args.log)
    csv = Path(args.csv) if args.csv else None
    figures = figure_paths(args.figures, f"{log_path.stem}_compare") if args.figures else []
    outputs = ([csv] if csv else []) + figures
    for path in outputs:
        if log_path.exists() and path.exists() and path.samefile(log_path):
            raise ValueError(f"{path} is the input log: choose another output file")
    check_logs_exist([log_path], "LOG")
    if args.figures:
        folder = Path(args.figures)
        if folder.exists() and not folder.is_dir():
            raise ValueError(f"{folder}: exists and is not a folder; give a folder to --figures")
        folder.mkdir(parents=True, exist_ok=True)
    check_writable(outputs, args.force)
    vehicle = vehicle_of(args.vehicle, args)
    signals = log_of(log_path, args)
    window = None
    if args.start is not None or args.end is not None:
        start = float(signals.t[0]) if args.start is None else args.start
        end = float(signals.t[-1]) if args.end is None else args.end
        window = (start, end)
    suspension = SuspensionModel.parse(args.suspension)
    print(f"{log_path.name} on vehicle '{vehicle.name}' ({args.vehicle})")
    print(f"family methods on the {suspension.value} vehicle model (--suspension)")
    comparison = compare_methods(
        signals, vehicle, names, window=window, repeat=args.repeat, suspension=suspension
    )
    print(format_table(comparison))
    if csv:
        write_csv(long_table(comparison), csv)
        print(f"table written to {csv}")
    if figures:
        title = f"{log_path.name}, {vehicle.name}"
        written = plot_comparison(comparison, signals, figures, title=title)
        print(f"figures written to {', '.join(str(p) for p in written)}")
    return 0
