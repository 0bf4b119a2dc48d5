"""Print the equilibrium residual per row on the plant's own loads, paper model vs terms.

``python -m wheelload.studies.experiments.equilibrium_table [SHORTEN]``: both bundled
vehicles, brake-in-turn, iso-dlc and the first ``SHORTEN`` (default 0.15) of
the Hockenheim lap, clean signals; RMS of ``b - A x_ref`` per row [N, N m, N m].
"""

from __future__ import annotations

import sys

from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenarios import scenario_run
from wheelload.studies.drive.simulation import simulate
from wheelload.studies.experiments.equilibrium_residuals import ROWS, paper_model, residual_rms

SCENARIOS = ("brake-in-turn", "iso-dlc", "hockenheim")


def main(shorten: float = 0.15) -> None:
    sports = example_vehicle_path()
    print(f"{'vehicle':<11}{'scenario':<15}" + "".join(f"{row:>18}" for row in ROWS))
    for path in (sports, sports.with_name("suv.toml")):
        vehicle = load_vehicle(path)
        for name in SCENARIOS:
            frame = simulate(vehicle, scenario_run(name, vehicle, Options(shorten=shorten))).frame
            paper = residual_rms(paper_model(vehicle), frame)
            terms = residual_rms(vehicle, frame)
            cells = "".join(f"{paper[row]:>9.0f} ->{terms[row]:>5.0f}" for row in ROWS)
            print(f"{vehicle.name:<11}{name:<15}{cells}")


if __name__ == "__main__":
    main(*(float(arg) for arg in sys.argv[1:]))
