"""Study ``cheon-structural`` (§IV-E2): the quarter-car observer E alone against E with the
KF's soft equilibrium update (E+C), with the KF (A) beside, on the Nordschleife, pooled."""

from __future__ import annotations

from wheelload.studies.experiments.report.paper_numbers import CHEON
from wheelload.studies.experiments.report.tables import markdown, pooled_table
from wheelload.studies.experiments.runs.common import Section, trials, truth_spec
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.units import TrialSpec

METHODS = ("E", "E+C", "kf")


def run(context: Context) -> Section:
    spec = TrialSpec(
        truth=truth_spec(context, "nordschleife"),
        vehicle_text=context.settings.vehicle_text,
        methods=METHODS,
    )
    result = trials(context, [spec], "cheon-structural")[0]
    table = pooled_table(result.metrics)
    context.outputs.write_text("cheon-structural_table.csv", table.to_csv(float_format="%.3f"))
    lines = []
    if {"E", "E+C"} <= result.metrics.keys():
        for i, column in enumerate(("RMSE", "P95", "Max")):
            e = float(result.metrics["E"].loc["pooled", column])
            ec = float(result.metrics["E+C"].loc["pooled", column])
            paper_e, paper_ec = CHEON["E"][i], CHEON["E+C"][i]
            lines.append(
                f"| {column} [N] | {e:.1f} | {ec:.1f} | {100 * (ec - e) / e:+.1f} % | "
                f"{paper_e:.1f} | {paper_ec:.1f} | {100 * (paper_ec - paper_e) / paper_e:+.1f} % |"
            )
    change = "\n".join(
        [
            "| metric | E | E+C | change | paper E | paper E+C | paper change |",
            "| --- | --- | --- | --- | --- | --- | --- |",
            *lines,
        ]
    )
    body = "\n\n".join(
        [
            "## Structural comparison: E alone and E + constraint update (§IV-E2)",
            markdown(table),
            change,
            "**Shape.** The paper finds the constraint update cuts E's pooled RMSE, P95 and Max "
            "by 45 %, 45 % and 36 %; the change column above gives ours.",
        ]
    )
    return Section(title="Cheon structural", markdown=body)
