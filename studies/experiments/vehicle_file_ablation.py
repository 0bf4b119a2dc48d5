"""Study ``ablation`` (Table V): the KF (method A) on the Nordschleife with its vehicle file
edited, pooled metrics per case.

Each case is a :class:`~wheelload.studies.experiments.runs.vehicle_variants.Variant`
of the estimator's vehicle file; the plant keeps the unedited file.
No aero: lift and drag coefficients 0. No ARB: bar rates 0. Symmetric
damper: push and pull coefficients both at their mean. No constraints: the
constraint noise density × 1e12 (the equilibrium update has no weight). Rc
scale k: the constraint noise density × k. Every boolean of the file's
``[model]`` section (the model-fidelity terms), when the file has one, adds a
case with that switch flipped.
"""

from __future__ import annotations

import tomllib

from wheelload.studies.experiments.report.paper_numbers import ABLATION
from wheelload.studies.experiments.report.shape import compare_ranking
from wheelload.studies.experiments.report.tables import markdown, pooled_table
from wheelload.studies.experiments.runs.common import Section, simulate, trials, truth_spec
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.units import TrialSpec
from wheelload.studies.experiments.runs.vehicle_variants import Edit, Variant, scaled, value

AXLES = ("suspension.front", "suspension.rear")
RC_SCALES = (0.25, 0.5, 2.0, 4.0)
NO_CONSTRAINT_SCALE = 1e12


def _damper(text: str, table: str) -> tuple[Edit, ...]:
    mean = 0.5 * (
        float(value(text, table, "damper_push")) + float(value(text, table, "damper_pull"))
    )
    return (Edit(table=table, key="damper_push", value=mean),
            Edit(table=table, key="damper_pull", value=mean))  # fmt: skip


def model_switches(text: str) -> list[Variant]:
    """One case per boolean of the ``[model]`` section, flipped (none if there is no section)."""
    table = tomllib.loads(text)
    if "model" not in table:
        return []
    return [
        Variant(
            label=f"model {key} {'off' if on else 'on'}",
            edits=(Edit(table="model", key=key, value=not on),),
        )  # fmt: skip
        for key, on in table["model"].items()
        if isinstance(on, bool)
    ]


def ablation_variants(text: str) -> list[Variant]:
    """The cases of Table V as edits of the vehicle file ``text``, then the model switches."""
    constraint = ("filter", "constraint_noise_density")
    return [
        Variant(label="baseline"),
        Variant(label="no aero", edits=(Edit(table="aero", key="lift_coefficient", value=0.0),
                                        Edit(table="aero", key="drag_coefficient", value=0.0))),
        Variant(label="no ARB", edits=tuple(Edit(table=a, key="arb_rate", value=0.0)
                                            for a in AXLES)),
        Variant(label="symmetric damper", edits=_damper(text, AXLES[0]) + _damper(text, AXLES[1])),
        Variant(label="no constraints", edits=(scaled(text, *constraint, NO_CONSTRAINT_SCALE),)),
        *[Variant(label=f"Rc scale {k:g}", edits=(scaled(text, *constraint, k),))
          for k in RC_SCALES],
        *model_switches(text),
    ]  # fmt: skip


def run(context: Context) -> Section:
    text = context.settings.vehicle_text
    truth = truth_spec(context, "nordschleife")
    simulate(context, [truth])
    variants = ablation_variants(text)
    specs = [TrialSpec(truth=truth, vehicle_text=v.apply(text), methods=("kf",)) for v in variants]
    results = trials(context, specs, "ablation")
    metrics = {v.label: r.metrics["kf"] for v, r in zip(variants, results) if "kf" in r.metrics}
    table = pooled_table(metrics)
    context.outputs.write_text("ablation_table.csv", table.to_csv(float_format="%.3f"))
    table["paper RMSE [N]"] = [ABLATION[k][0] if k in ABLATION else float("nan")
                               for k in table.index]  # fmt: skip
    table["paper P95 [N]"] = [ABLATION[k][2] if k in ABLATION else float("nan")
                              for k in table.index]  # fmt: skip
    ours = {k: float(m.loc["pooled", "RMSE"]) for k, m in metrics.items()}
    paper = {k: v[0] for k, v in ABLATION.items()}
    switches = model_switches(text)
    note = (
        f"The model-fidelity terms add {len(switches)} cases (the file's `[model]` switches)."
        if switches
        else "The model-fidelity terms (issue 9) are not yet in this vehicle file: no `[model]` "
        "section, so no case for them; each of its switches becomes a case when it lands."
    )
    body = "\n\n".join(
        [
            "## Ablation on the Nordschleife, method A (Table V)",
            "The plant keeps the vehicle file; the KF's copy is edited. "
            "Pooled over wheels and samples; the paper's RMSE and P95 beside.",
            markdown(table),
            "**Shape.** " + compare_ranking(ours, paper, "pooled RMSE over the ablation cases"),
            note,
        ]
    )
    return Section(title="Ablation", markdown=body)
