"""Study ``vehicles``: the headline table (every method, pooled, Hockenheim lap) on every
bundled vehicle file (``models/vehicles/*.toml``), each simulated and estimated with itself."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from wheelload.studies.experiments.report.tables import markdown
from wheelload.studies.experiments.runs.common import Section, all_methods, trials, truth_spec
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.units import TrialSpec

SCENARIO = "hockenheim"


def vehicle_files(folder: Path) -> list[Path]:
    """The bundled vehicle files, sorted by name."""
    return sorted(Path(folder).glob("*.toml"))


def run(context: Context) -> Section:
    paths = vehicle_files(context.settings.vehicles_folder)
    specs = []
    for path in paths:
        text = path.read_text(encoding="utf-8")
        specs.append(
            TrialSpec(
                truth=truth_spec(context, SCENARIO, vehicle_text=text),
                vehicle_text=text,
                methods=all_methods(),
            )  # fmt: skip
        )
    results = trials(context, specs, "vehicles")
    columns = {}
    for path, result in zip(paths, results):
        for metric in ("RMSE", "RMSE %", "P95", "Max"):
            columns[(path.stem, metric)] = {
                name: float(table.loc["pooled", metric]) for name, table in result.metrics.items()
            }
    table = pd.DataFrame(columns)
    table.index.name = "method"
    context.outputs.write_text("vehicles_table.csv", table.to_csv(float_format="%.3f"))
    flat = table.copy()
    flat.columns = [f"{v} {m}" for v, m in flat.columns]
    names = ", ".join(p.stem for p in paths)
    body = "\n\n".join(
        [
            f"## Every method on each bundled vehicle ({names}), {SCENARIO} lap, pooled",
            markdown(flat, digits=1),
            f"{len(paths)} vehicle file(s) found in `models/vehicles/`; a file added there "
            "appears here on the next run.",
        ]
    )
    return Section(title="Vehicles", markdown=body)
