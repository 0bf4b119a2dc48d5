"""``wheelload identify-study``: a wrong vehicle file put right by identify and tune, on the plant.

Prints two tables (``studies/identification_study.py``): the two-stage KF's
pooled RMSE with the true, the wrong (springs -20 %, dampers +30 %, bars
-30 %) and the identified file on scenarios not used for identification;
and ±2σ coverage and RMSE of the input and the tuned filter on logs not used
for tuning. ``--quick`` uses three scenarios.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.studies.identification_study import StudySettings, run_study

QUICK = ("accel-in-turn", "iso-dlc", "slope-20")


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "identify-study",
        help="identify and tune from a wrong vehicle file on plant logs; print the tables",
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("--out", default="identify-study", help="folder for logs and tables")
    parser.add_argument("--quick", action="store_true", help="three scenarios only")
    parser.set_defaults(handler=handle)


def handle(args: argparse.Namespace) -> int:
    settings = StudySettings(scenarios=QUICK) if args.quick else StudySettings()
    folder = Path(args.out)
    identification, tuning = run_study(settings, folder)
    for name, frame in (("identification", identification), ("tuning", tuning)):
        target = folder / f"{name}.csv"
        frame.to_csv(target, index=False, float_format="%.6g")
    print(
        f"KF pooled RMSE [N]; file identified from {settings.identify_on} "
        f"(start: springs x{settings.spring}, dampers x{settings.damper}, bars x{settings.bar})"
    )
    print(identification.to_string(index=False, float_format="%.1f"))
    print(
        f"\ntuned on {', '.join(settings.tune_on)}: [q, r_s, r_c, r_sv, r_sh, r_ca] ="
        f" {tuning.attrs['tuned']}"
    )
    print(tuning.to_string(index=False, float_format="%.1f"))
    print(f"tables written to {folder}")
    return 0
