"""``wheelload bench hostile``: the estimators on hostile inputs, printed (issue 21).

Rows: the two-stage KF in Python, its generated C in double and in float, and
the embedded MHE's C (``codegen --estimator mhe``: soft, bounded, N = 10, the KF
linked in). Columns: sanitizer findings (C built with
``-fsanitize=address,undefined``), non-finite outputs, max :math:`|F_z|` (and
whether it is within :math:`2 m g`), steps locked out. The log: a plant
scenario with every input channel corrupted at each ``--fractions`` share of
its samples (:func:`wheelload.studies.experiments.faults.hostile.hostile_frame`).

``--envelope N`` also runs the envelope property on N unseeded white-noise
logs (:func:`~wheelload.studies.experiments.faults.hostile.white_noise_signals`) and prints the
largest excursion of the KF's total load from the log's own vertical-row range;
``--ranges`` prints the body-rate ranges of the plant's scenarios that the
guard settings were chosen from.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators import StepFlag
from wheelload.estimators.codegen.kf import STRICT_CFLAGS, CodegenOptions, build_program, generate
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.logs.signals import derive_velocities, signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models import GRAVITY, example_vehicle_path, load_vehicle
from wheelload.models.conventions import WHEELS
from wheelload.studies.commands.options import add_allow_unusual, add_vehicle_option
from wheelload.studies.experiments.faults import hostile

SCENARIOS = (
    "iso-dlc", "hockenheim", "nordschleife", "brake-in-turn", "accel-in-turn", "bounce-sweep",
    "slope-20", "chicane-bank-30", "chicane-incline-20", "wheel-lift",
)  # fmt: skip


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench hostile``."""
    parser = subparsers.add_parser("hostile")
    add_vehicle_option(parser)
    parser.add_argument("--scenario", default="iso-dlc", help="plant scenario (default iso-dlc)")
    parser.add_argument(
        "--fractions", default="0.001,0.01,0.1", help="shares of corrupted samples (0.1-10 %%)"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the corruptions")
    parser.add_argument("--no-mhe", action="store_true", help="leave the embedded MHE out")
    parser.add_argument("--envelope", type=int, default=0, help="white-noise logs to run")
    parser.add_argument(
        "--ranges", action="store_true", help="print the scenarios' rate ranges (both vehicles)"
    )
    add_allow_unusual(parser)
    parser.set_defaults(handler=run)


def _c_kf(vehicle_path, frame, folder: Path, precision: Precision) -> hostile.HostileSummary:
    library = generate(vehicle_path, folder, CodegenOptions(precision=precision))
    binary = build_program(
        library, library.example, folder / "example", flags=(*STRICT_CFLAGS, *hostile.SANITIZE)
    )
    log = hostile.write_frame(frame, folder / "hostile.csv")
    done = hostile.run_binary([str(binary), str(log), str(folder / "estimates.csv")])
    if done.returncode != 0:
        raise RuntimeError(f"{binary} failed ({done.returncode}): {done.stderr[-2000:]}")
    out = pd.read_csv(folder / "estimates.csv")
    std = out[[f"fz_std_{w}" for w in WHEELS]]
    return hostile.summarise(
        f"KF C {precision.value}", out[hostile.LOADS], std, out["status"],
        hostile.sanitizer_reports(done.stderr),
    )  # fmt: skip


def _c_mhe(vehicle, vehicle_path, signals, folder: Path) -> hostile.HostileSummary:
    from wheelload.estimators import Constraint, MheSettings
    from wheelload.estimators.codegen.mhe import embedded_settings
    from wheelload.estimators.codegen.mhe_build import build_mhe_program, write_inputs

    settings = embedded_settings(MheSettings(horizon=10, constraint=Constraint.SOFT, bounded=True))
    dt = float(np.median(np.diff(signals.t)))
    binary = build_mhe_program(
        vehicle, settings, folder, dt, flags=("-O2", *hostile.SANITIZE),
        vehicle_path=Path(vehicle_path),
    )  # fmt: skip
    inputs = write_inputs(signals, folder / "inputs.txt")
    done = hostile.run_binary([str(binary), str(inputs), str(folder / "mhe.csv")])
    reports = hostile.sanitizer_reports(done.stderr)
    if done.returncode != 0 and not reports:
        raise RuntimeError(f"{binary} failed ({done.returncode}): {done.stderr[-2000:]}")
    out = pd.read_csv(folder / "mhe.csv")
    std = out[[f"std_{w}" for w in WHEELS]]
    return hostile.summarise("MHE C (embedded)", out[hostile.LOADS], std, out["flags"], reports)


#: Flags of a clean sample the new guards must never raise.
_CLEAN_BITS = (
    StepFlag.RATE_IMPLAUSIBLE | StepFlag.INPUT_HELD | StepFlag.LOAD_LIMITED
    | StepFlag.ACCELERATION_IMPLAUSIBLE | StepFlag.TRAVEL_IMPLAUSIBLE
)  # fmt: skip


def _ranges(vehicle_paths) -> None:
    """Largest |w|, |dw|/dt and differentiator |w_dot| per scenario, smooth and rough D,
    and the clean samples the KF flags as implausible, held or load-limited."""
    from wheelload.studies.drive.scenario_options import Options
    from wheelload.studies.drive.scenario_runner import run_scenario

    print("scenario, vehicle, roughness: max |w| [rad/s], max |dw|/dt, max |w_dot| [rad/s^2],"
          " samples, flagged")  # fmt: skip
    worst = np.zeros(3)
    for path in vehicle_paths:
        kf = build("kf", load_vehicle(path))
        for name in SCENARIOS:
            for roughness in (None, "D"):
                options = Options(roughness=roughness) if roughness else Options()
                log = run_scenario(name, path, options=options).log
                t, w = log["t"].to_numpy(), log[["wx", "wy", "wz"]].to_numpy()
                jump = np.abs(np.diff(w, axis=0)).max() / np.median(np.diff(t))
                dot = np.nanmax(np.abs(derive_velocities(t, w)))
                row = np.array([np.abs(w).max(), jump, dot])
                worst = np.maximum(worst, row)
                flags = kf.run(signals_from_frame(log, source=name)).flags
                flagged = np.count_nonzero(flags & _CLEAN_BITS)
                label = f"{name:20s} {Path(path).stem:10s} {roughness or '-':2s}"
                numbers = f"{row[0]:6.3f} {row[1]:7.2f} {row[2]:7.2f} {len(flags):7d} {flagged}"
                print(f"  {label} {numbers}")
    print(f"largest: |w| {worst[0]:.3f} rad/s, |dw|/dt {worst[1]:.2f}, |w_dot| {worst[2]:.2f}")


def _envelope(vehicle, runs: int) -> None:
    from wheelload.studies.drive.synthetic import slalom, synthetic_log

    kf = build("kf", vehicle)
    base = synthetic_log(vehicle, slalom(duration=3.0), seed=1)
    seeds = np.random.SeedSequence().generate_state(runs)
    excess = [
        hostile.envelope_excess(kf, s, kf.run(s).loads)
        for s in (hostile.white_noise_signals(vehicle, base, int(seed)) for seed in seeds)
    ]
    weight = vehicle.mass.total * GRAVITY
    print(f"envelope: {runs} unseeded white-noise logs of 300 samples: largest excursion of "
          f"the total load from the log's own vertical-row range {max(excess):.0f} N "
          f"({max(excess) / weight:.3f} m g; the guard's margin is "
          f"{kf.guard_settings.total_margin} m g)")  # fmt: skip


def run(args: argparse.Namespace) -> int:
    from wheelload.studies.drive.scenario_runner import run_scenario

    vehicle_path = args.vehicle or example_vehicle_path()
    vehicle = load_vehicle(vehicle_path, allow_unusual=args.allow_unusual)
    weight = vehicle.mass.total * GRAVITY
    if args.ranges:
        from wheelload.studies.experiments.faults.fault_injection import bundled_vehicles

        _ranges([args.vehicle] if args.vehicle else bundled_vehicles())
    clean = run_scenario(args.scenario, vehicle_path).log
    signals = signals_from_frame(clean, source=args.scenario)
    frame = hostile.with_rate_derivatives(clean, signals)
    header = ["estimator", "sanitizer", "non-finite", "max |Fz| [N]", "<= 2 m g", "locked out"]
    for fraction in (float(f) for f in args.fractions.split(",")):
        bad = hostile.hostile_frame(frame, fraction, args.seed)
        bad_signals = hostile.with_inputs(signals, bad)
        start = time.perf_counter()
        rows = []
        estimate = build("kf", vehicle).run(bad_signals)
        rows.append(hostile.summarise("KF Python", estimate.loads, estimate.std,
                                      estimate.flags, None))  # fmt: skip
        with tempfile.TemporaryDirectory(prefix="wheelload-hostile-") as folder:
            for precision in Precision:
                target = Path(folder) / precision.value
                rows.append(_c_kf(vehicle_path, bad, target, precision))
            if not args.no_mhe:
                rows.append(_c_mhe(vehicle, vehicle_path, bad_signals, Path(folder) / "mhe"))
        print(f"\n{args.scenario}, {100 * fraction:g} % of the samples of every channel "
              f"corrupted (seed {args.seed}; 2 m g = {2 * weight:.0f} N; "
              f"{time.perf_counter() - start:.0f} s)")  # fmt: skip
        table = [header, *[row.row(weight) for row in rows]]
        widths = [max(len(r[k]) for r in table) for k in range(len(header))]
        for r in table:
            cells = [r[0].ljust(widths[0])]
            cells += [cell.rjust(width) for cell, width in zip(r[1:], widths[1:], strict=True)]
            print("  ".join(cells))
    if args.envelope:
        _envelope(vehicle, args.envelope)
    return 0
