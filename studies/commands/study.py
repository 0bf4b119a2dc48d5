"""``wheelload study NAME``: one comparison study, its table printed and written.

``mhe-vs-kf`` scores the KF, projection KF and MHE family on logs (``--logs``)
or on plant scenarios it simulates first (``--scenarios``); every other name is
an experiment of :mod:`~wheelload.studies.experiments.catalog`, run into the
folder ``--out DIR``, which is locked before any work
(:mod:`~wheelload.studies.experiments.runs.folder_lock`), so a second study into
it refuses at once.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import (
    WORKERS,
    CommandTraits,
    add_common_options,
    add_suspension_option,
    add_vehicle_option,
    check_logs_exist,
    refuse_unused,
    show_progress,
    told,
    vehicle_file,
    vehicle_for_logs,
)
from wheelload.studies.experiments.runs import choices
from wheelload.studies.experiments.runs.choices import EstimatorModel

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(log=True, vehicle=True, writes=True, many_logs=True)

#: The options of mhe-vs-kf only (None or False on the parser: given or not).
MHE_VS_KF = ("--logs", "--scenarios", "--sweep", "--faults", "--horizon", "--horizons",
             "--channels", "--skip-wiring-checks")  # fmt: skip


def register(subparsers: argparse._SubParsersAction) -> None:
    study = subparsers.add_parser("study", help=CATALOG["study"].summary)
    study.add_argument(
        "name",
        choices=["mhe-vs-kf", *choices.EXPERIMENT_NAMES],
        help="mhe-vs-kf: KF, projection KF, MHE; the others: studies/experiments/",
    )
    study.add_argument("--logs", nargs="+", metavar="LOG",
                       help="mhe-vs-kf: logs with reference loads")  # fmt: skip
    study.add_argument(
        "--scenarios", nargs="*",
        help="mhe-vs-kf: simulate these plant scenarios first (no names: "
        + ", ".join(choices.STUDY_SCENARIOS) + ", those that exist)",
    )  # fmt: skip
    study.add_argument(
        "--sweep", choices=["robust", "equivalence"],
        help="mhe-vs-kf: robust (default): robust losses, bias states, lagged output and the "
        "RTS smoother on clean and faulted logs; equivalence: KF, projection KF, plain MHEs",
    )  # fmt: skip
    study.add_argument("--faults", nargs="+", choices=[f.value for f in choices.Fault],
                       help="mhe-vs-kf robust sweep: faults injected (default: all)")  # fmt: skip
    study.add_argument("--horizon", type=int,
                       help="mhe-vs-kf robust sweep: window length (default 10)")  # fmt: skip
    study.add_argument(
        "--quick", action="store_true",
        help="short segments, few trials; mhe-vs-kf robust sweep: the KF with and without its "
        "guards, RTS, the lagged and the Huber 0.5σ MHE only",
    )  # fmt: skip
    horizons = " ".join(map(str, choices.HORIZONS))
    study.add_argument("--horizons", type=int, nargs="+",
                       help=f"mhe-vs-kf equivalence: window lengths ({horizons})")  # fmt: skip
    study.add_argument(
        "--out", metavar="PREFIX|DIR",
        help="prefix for mhe-vs-kf: PREFIX.csv and PREFIX-vs-kf.csv or PREFIX.png (default "
        "mhe-vs-kf); folder for the others: tables, figures, REPORT.md (required)",
    )  # fmt: skip
    add_vehicle_option(study)
    # the experiments' own options (--quick, --force and --out are shared with mhe-vs-kf)
    study.add_argument("--cache", metavar="DIR",
                       help="folder of the results cache (default DIR/.cache)")  # fmt: skip
    add_suspension_option(study)
    study.add_argument(
        "--model",
        metavar="{" + ",".join(m.value for m in EstimatorModel) + "}",
        default=EstimatorModel.FULL.value,
        help="vehicle model of kf, projection and mhe (and of the family methods with "
        f"--suspension full, the KF's own model): full = {choices.WORDS[EstimatorModel.FULL]} "
        f"(default); paper = {choices.WORDS[EstimatorModel.PAPER]}. "
        "The plant keeps the vehicle file",
    )
    add_common_options(study, TRAITS)
    study.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    model = EstimatorModel.parse(args.model)  # a wrong name is one line, before any work
    if args.name != "mhe-vs-kf":
        refuse_unused(args, dict.fromkeys(MHE_VS_KF), f"study {args.name}")
        return _experiment(args, model)
    from wheelload.estimators import DEFAULT_MODEL

    unused = {"--cache": None, "--dask": None, "--workers": WORKERS, "--no-progress": False,
              "--suspension": DEFAULT_MODEL.value}  # fmt: skip
    refuse_unused(args, unused, "study mhe-vs-kf (the KF, projection KF and MHE only)")
    sweep = args.sweep or "robust"
    other = ("--horizons",) if sweep == "robust" else ("--faults", "--horizon", "--quick")
    refuse_unused(args, dict.fromkeys(other), f"study mhe-vs-kf --sweep {sweep}")
    if args.horizon is not None and args.horizon < 2:
        raise ValueError("--horizon must be >= 2 for the robust sweep (the lagged output)")
    return _mhe_vs_kf(args, model)


def _mhe_vs_kf(args: argparse.Namespace, model: EstimatorModel) -> int:
    """The mhe-vs-kf study: the robust sweep (default) or the equivalence sweep and figure."""
    from wheelload.estimators import read_log
    from wheelload.estimators.logs.output_files import atomic_write, check_outputs
    from wheelload.models import load_vehicle
    from wheelload.studies.experiments import mhe_vs_kf
    from wheelload.studies.experiments.runs.estimator_model import on_model

    paths = [Path(p) for p in args.logs or ()]
    given = set(paths)
    check_logs_exist(paths, "--logs")
    out = Path(args.out or "mhe-vs-kf")
    second = (out.with_name(out.name + "-vs-kf.csv") if args.sweep != "equivalence"
              else out.with_suffix(".png"))  # fmt: skip
    outputs = [out.with_suffix(".csv"), second]
    check_outputs(outputs, [*paths, *([args.vehicle] if args.vehicle else [])], force=args.force)
    vehicle_path = vehicle_for_logs(args, paths)
    vehicle = on_model(load_vehicle(vehicle_path, allow_unusual=args.allow_unusual), model)
    if args.scenarios is None and not paths:
        raise ValueError("give --logs or --scenarios")
    told(args)  # the arguments are checked: the work starts
    with tempfile.TemporaryDirectory() as folder:
        if args.scenarios is not None:
            from wheelload.studies.drive.scenario_runner import simulate_logs
            from wheelload.studies.drive.scenarios import SCENARIOS

            default = [name for name in choices.STUDY_SCENARIOS if name in SCENARIOS]
            names = args.scenarios or default
            simulated = simulate_logs(names, Path(folder), vehicle_path, args.allow_unusual)
            for name, path, samples in simulated:
                print(f"{name}: {samples} samples simulated")
                paths.append(path)
        logs = [read_log(path, channels=args.channels if path in given else None,
                         wiring_checks=not args.skip_wiring_checks) for path in paths]  # fmt: skip
    print(f"vehicle '{vehicle.name}' ({vehicle_path}), model {model.value} (--model)")
    if args.sweep != "equivalence":
        return _robust(args, logs, paths, vehicle)
    horizons = tuple(args.horizons or choices.HORIZONS)
    table = mhe_vs_kf.mhe_vs_kf(logs, vehicle, mhe_vs_kf.StudySettings(horizons=horizons))
    with atomic_write(outputs[0], replace=args.force) as temporary:
        table.to_csv(temporary)
    with atomic_write(outputs[1], replace=args.force) as temporary:
        mhe_vs_kf.plot_accuracy_against_time(table, temporary)
    print(f"logs: {', '.join(str(p.name) for p in paths)} ({sum(map(len, logs))} samples)")
    print(table.to_string(float_format=lambda v: f"{v:.1f}"))
    print(f"written {out.with_suffix('.csv')} and {out.with_suffix('.png')}")
    return 0


def _robust(args: argparse.Namespace, logs, paths, vehicle) -> int:
    """The robust sweep: RMSE table, change against the KF, written as CSV."""
    from wheelload.estimators.logs.output_files import atomic_write
    from wheelload.studies.experiments import mhe_vs_kf

    horizon = 10 if args.horizon is None else args.horizon
    faults = tuple(choices.Fault(n) for n in args.faults or [f.value for f in choices.Fault])
    candidates = mhe_vs_kf.robust_candidates(horizon, quick=args.quick)
    table = mhe_vs_kf.robust_sweep(logs, vehicle, faults, candidates)
    change = mhe_vs_kf.against_kf(table, faults)
    out = Path(args.out or "mhe-vs-kf")
    for frame, path in ((table, out.with_suffix(".csv")),
                        (change, out.with_name(out.name + "-vs-kf.csv"))):  # fmt: skip
        with atomic_write(path, replace=args.force) as temporary:
            frame.to_csv(temporary)
    print(f"logs: {', '.join(str(p.name) for p in paths)} ({sum(map(len, logs))} samples)")
    print("pooled RMSE [N] per injected fault (reference: the clean log's loads)")
    print(table.to_string(float_format=lambda v: f"{v:.1f}"))
    print("change against the two-stage KF (with its guards) on the same fault [%]")
    print(change.to_string())
    if mhe_vs_kf.PLAIN_KF in table.index:
        print("change against the plain KF (no guards) on the same fault [%]")
        print(mhe_vs_kf.against_kf(table, faults, mhe_vs_kf.PLAIN_KF).to_string())
    print(f"written {out.with_suffix('.csv')} and {out.with_name(out.name + '-vs-kf.csv')}")
    return 0


def _experiment(args: argparse.Namespace, model: EstimatorModel) -> int:
    """Run experiment ``args.name`` into ``args.out``; print what was computed and cached."""
    from wheelload.studies.experiments.runs.folder_lock import folder_lock

    if args.name not in choices.EXPERIMENT_NAMES:
        names = ", ".join(choices.EXPERIMENT_NAMES)
        raise ValueError(f"unknown study '{args.name}'; choose from mhe-vs-kf, {names}")
    if args.out is None:
        raise ValueError(f"study {args.name} needs --out DIR (a folder for tables and figures)")
    if args.workers < 1:
        raise ValueError(f"--workers must be >= 1, got {args.workers}")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: exists and is not a folder; give a folder to --out")
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out):  # before any work: a second study into ``out`` refuses at once
        return _run_experiment(args, out, model)


def _run_experiment(args: argparse.Namespace, out: Path, model: EstimatorModel) -> int:
    from wheelload.estimators import SuspensionModel
    from wheelload.models import example_vehicle_path
    from wheelload.studies.experiments import catalog as experiments
    from wheelload.studies.experiments.runs.cache import ResultCache
    from wheelload.studies.experiments.runs.context import Context, Outputs, Settings
    from wheelload.studies.experiments.runs.runner import Runner, check_scheduler

    vehicle_path = vehicle_file(args)
    if not vehicle_path.is_file():
        raise ValueError(f"{vehicle_path}: no such vehicle file (--vehicle)")
    if args.dask is not None:
        check_scheduler(args.dask)
    settings = Settings(
        vehicle_path=vehicle_path,
        vehicles_folder=example_vehicle_path().parent,
        quick=args.quick,
        suspension=SuspensionModel.parse(args.suspension),
        model=model,
    )
    runner = Runner(
        cache=ResultCache(folder=Path(args.cache) if args.cache else out / ".cache"),
        workers=args.workers,
        dask_address=args.dask,
        progress=show_progress(args),
    )
    outputs = Outputs(folder=out, force=args.force)
    # the vehicle's line waits for the end: a refusal inside the run (lock, cache) is one line
    start = time.perf_counter()
    with runner:
        experiments.run_study(args.name, Context(settings=settings, runner=runner, outputs=outputs))
    print(
        f"study {args.name} on vehicle '{settings.vehicle_name}': {runner.computed} jobs "
        f"computed, {runner.cached} from the cache, "
        f"{time.perf_counter() - start:.1f} s; {len(outputs.written)} files in {out}"
    )
    return 0
