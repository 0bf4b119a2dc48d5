"""Study ``mismatch``: every method with its vehicle file off by ±20 % in springs, dampers,
anti-roll bars, sprung mass and CG height (the plant keeps the true file), on the
Hockenheim lap; pooled RMSE per method and case. No paper gives this table."""

from __future__ import annotations

import pandas as pd

from wheelload.models.conventions import SUSPENSION_TABLES
from wheelload.studies.experiments.report.tables import markdown
from wheelload.studies.experiments.runs.common import Section, all_methods, trials, truth_spec
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.units import TrialSpec
from wheelload.studies.experiments.runs.vehicle_variants import Edit, Variant, scaled, value

SCENARIO = "hockenheim"
ERROR = 0.20


def mass_edits(text: str, factor: float) -> tuple[Edit, ...]:
    """The edits that scale the sprung mass by ``factor`` (and the total with it)."""
    sprung = factor * float(value(text, "mass", "sprung"))
    unsprung = float(value(text, "mass", "unsprung_front")) + float(
        value(text, "mass", "unsprung_rear")
    )
    return (Edit(table="mass", key="sprung", value=sprung),
            Edit(table="mass", key="total", value=sprung + unsprung))  # fmt: skip


def mismatch_variants(text: str) -> list[Variant]:
    """The true file, then each parameter group scaled by 1 - ERROR and 1 + ERROR."""
    variants = [Variant(label="true")]
    for sign in (-1.0, 1.0):
        k = 1.0 + sign * ERROR
        tag = f"{sign * ERROR * 100:+.0f} %"
        variants += [
            Variant(label=f"springs {tag}",
                    edits=tuple(scaled(text, a, "spring_rate", k) for a in SUSPENSION_TABLES)),
            Variant(label=f"dampers {tag}",
                    edits=tuple(scaled(text, a, key, k) for a in SUSPENSION_TABLES
                                for key in ("damper_push", "damper_pull"))),
            Variant(label=f"ARB {tag}",
                    edits=tuple(scaled(text, a, "arb_rate", k) for a in SUSPENSION_TABLES)),
            Variant(label=f"mass {tag}", edits=mass_edits(text, k)),
            Variant(label=f"CG height {tag}", edits=(scaled(text, "geometry", "cg_height", k),)),
        ]  # fmt: skip
    return variants


def run(context: Context) -> Section:
    text = context.settings.vehicle_text
    truth = truth_spec(context, SCENARIO)
    variants = mismatch_variants(text)
    names = all_methods()
    specs = [TrialSpec(truth=truth, vehicle_text=v.apply(text), methods=names) for v in variants]
    results = trials(context, specs, "mismatch")
    table = pd.DataFrame(
        {
            v.label: {n: float(r.metrics[n].loc["pooled", "RMSE"]) if n in r.metrics
                      else float("nan") for n in names}
            for v, r in zip(variants, results)
        }
    )  # fmt: skip
    table.index.name = "method"
    context.outputs.write_text("mismatch_table.csv", table.to_csv(float_format="%.3f"))
    worst = table.drop(columns="true").max(axis=1)
    growth = (100.0 * (worst / table["true"] - 1.0)).sort_values()
    worst_case = table.drop(columns="true").idxmax(axis=1)
    ranking = ", ".join(f"{m} {growth[m]:+.0f} % ({worst_case[m]})" for m in growth.index)
    body = "\n\n".join(
        [
            f"## Parameter mismatch on the {SCENARIO} lap (pooled RMSE [N])",
            "Each column: the estimators' vehicle file with one parameter group off by "
            f"{ERROR:.0%}; the plant keeps the true file. No paper gives this table.",
            markdown(table.T.rename_axis("case"), digits=1),
            "**Robustness**, worst-case growth of pooled RMSE over the true file (worst case): "
            + ranking
            + ".",
        ]
    )
    return Section(title="Mismatch", markdown=body)
