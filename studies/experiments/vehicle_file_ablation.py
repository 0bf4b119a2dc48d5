"""Study ``ablation`` (Table V): the KF (method A) on the Nordschleife with its vehicle file
edited, pooled metrics per case, the paper's RMSE, RMSE %, P95 and Max beside.

Each case is a :class:`~wheelload.studies.experiments.runs.vehicle_variants.Variant`
of the estimator's vehicle file; the plant keeps the unedited file. Each edit changes
the one thing the paper's does (§IV-E1):

- No aero: "removing the aerodynamic vertical force term from the vertical equilibrium
  constraint", i.e. the lift coefficient 0. The drag coefficient is held: drag enters
  only the pitch row, :math:`(h + z_a) D` (eq. 16), which the paper's edit leaves.
- No ARB: "disabling the ARB contribution", the bar rates 0, so the bar force
  :math:`F^{arb}_i` leaves the pseudo-measurement (eq. 6-9). The roll split is held:
  the file's ``suspension.roll_split_front`` is set to the unedited file's value
  (by default the front share of the springs' and bars' roll stiffness, which a bar rate
  of 0 would move from 0.489 to 0.477 on the sports car), so the split row of
  :mod:`wheelload.models.roll_split` keeps its weight direction. That row is used only
  when no travel sensor is logged, so on this study's logs holding it changes no number;
  it makes the edit one change for every sensor set. With the full model's
  ``road_frame`` term the bar rate also sets the tyre deflection under the bar's load in
  the road-frame attitude (:func:`~wheelload.models.terms.corner_deflection`); the paper's
  model has no such term, and the file has no switch to hold it apart.
- Symmetric damper: push and pull coefficients both at their mean.
- No constraints: the constraint noise density × 1e12 (the equilibrium update has no
  weight). Rc scale k: the constraint noise density × k.

Every boolean of the file's ``[model]`` section (the model-fidelity terms), when the
file has one, adds a case with that switch flipped; on the paper's model (``--model paper``,
:mod:`~wheelload.studies.experiments.runs.estimator_model`: every term off) there is none.

The Rc sweep's optimum is set beside the filter's noise calibration on the same log
(:func:`~wheelload.studies.experiments.equilibrium_residuals.noise_calibration`): the
mean square of each update's actual error (pseudo-measurement, equilibrium rows, on the
reference loads) over the variance the filter assumes for it.
"""

from __future__ import annotations

import tomllib
from dataclasses import replace

import numpy as np

from wheelload.models import ModelParameters
from wheelload.models.conventions import SUSPENSION_TABLES
from wheelload.models.vehicle.description import vehicle_from_dict
from wheelload.studies.experiments.equilibrium_residuals import noise_calibration
from wheelload.studies.experiments.report.paper_numbers import ABLATION
from wheelload.studies.experiments.report.shape import compare_ranking
from wheelload.studies.experiments.report.tables import markdown, pooled_table
from wheelload.studies.experiments.runs.cache import cache_key
from wheelload.studies.experiments.runs.common import Section, simulate, trials, truth_spec
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.estimator_model import EstimatorModel, on_model
from wheelload.studies.experiments.runs.units import TRUTH, TrialSpec, measured
from wheelload.studies.experiments.runs.vehicle_variants import Edit, Variant, scaled, value

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


def held_roll_split(text: str, model: EstimatorModel = EstimatorModel.FULL) -> Edit:
    """``suspension.roll_split_front`` set to the value the unedited file ``text`` gives the
    filter on ``model`` (its own, or the default of its springs and bars)."""
    vehicle = on_model(vehicle_from_dict(tomllib.loads(text)), model)
    split = float(ModelParameters.from_vehicle(vehicle).roll_split_front)
    return Edit(table="suspension", key="roll_split_front", value=split, optional=True)


def ablation_variants(text: str, model: EstimatorModel = EstimatorModel.FULL) -> list[Variant]:
    """The cases of Table V as edits of the vehicle file ``text``, then the model switches
    (none on the paper's model, whose terms are all off)."""
    constraint = ("filter", "constraint_noise_density")
    no_bars = tuple(Edit(table=a, key="arb_rate", value=0.0) for a in SUSPENSION_TABLES)
    switches = model_switches(text) if model is EstimatorModel.FULL else []
    return [
        Variant(label="baseline"),
        Variant(label="no aero", edits=(Edit(table="aero", key="lift_coefficient", value=0.0),)),
        Variant(label="no ARB", edits=(*no_bars, held_roll_split(text, model))),
        Variant(label="symmetric damper",
                edits=tuple(e for table in SUSPENSION_TABLES for e in _damper(text, table))),
        Variant(label="no constraints", edits=(scaled(text, *constraint, NO_CONSTRAINT_SCALE),)),
        *[Variant(label=f"Rc scale {k:g}", edits=(scaled(text, *constraint, k),))
          for k in RC_SCALES],
        *switches,
    ]  # fmt: skip


def rc_words(ours: dict[str, float], calibration: dict[str, float]) -> str:
    """Sentences placing the sweep's best Rc scale beside the filter's noise calibration
    (:func:`~wheelload.studies.experiments.equilibrium_residuals.noise_calibration`)."""
    sweep = {1.0: ours.get("baseline", float("nan"))}
    sweep.update({k: ours.get(f"Rc scale {k:g}", float("nan")) for k in RC_SCALES})
    finite = {k: v for k, v in sweep.items() if np.isfinite(v)}
    if not finite:
        return "No Rc case ran."
    best = min(finite, key=finite.get)
    rows = ("vertical", "pitch", "roll")
    ratios = [calibration[row] / calibration["suspension"] for row in rows]
    cells = ", ".join(f"{row} {calibration[row]:.3g}" for row in rows)
    matched = ", ".join(f"{row} × {r:.2g}" for row, r in zip(rows, ratios, strict=True))
    return (
        f"The pooled RMSE is lowest at Rc × {best:g} ({finite[best]:.1f} N; "
        + ", ".join(f"× {k:g}: {v:.1f}" for k, v in sorted(finite.items()))
        + "). On this log the mean of e²/R (actual error squared over the variance the "
        f"filter assumes) is {calibration['suspension']:.3g} for the pseudo-measurement and "
        f"{cells} for the equilibrium rows: weighing the two updates as their errors are "
        f"would scale Rc by {matched} (white-noise view; the errors are correlated in time, "
        "which the filter's weights do not know). One scale moves the three rows together, "
        f"while their ratios span × {min(ratios):.2g} to × {max(ratios):.2g}: the sweep's "
        "optimum is the compromise between the rows this log weighs most. The paper reports "
        "its optimum at its nominal × 1."
    )


def run(context: Context) -> Section:
    text, model = context.settings.vehicle_text, context.settings.model
    truth = truth_spec(context, "nordschleife")
    simulate(context, [truth])
    variants = ablation_variants(text, model)
    specs = [TrialSpec(truth=truth, vehicle_text=v.apply(text), methods=("kf",)) for v in variants]
    results = trials(context, specs, "ablation")
    metrics = {v.label: r.metrics["kf"] for v, r in zip(variants, results) if "kf" in r.metrics}
    table = pooled_table(metrics)
    context.outputs.write_text("ablation_table.csv", table.to_csv(float_format="%.3f"))
    for i, column in enumerate(("RMSE [N]", "RMSE [%]", "P95 [N]", "Max [N]")):
        table[f"paper {column}"] = [ABLATION[k][i] if k in ABLATION else float("nan")
                                    for k in table.index]  # fmt: skip
    ours = {k: float(m.loc["pooled", "RMSE"]) for k, m in metrics.items()}
    paper = {k: v[0] for k, v in ABLATION.items()}
    log = measured(
        replace(specs[0], truth_key=cache_key(TRUTH, truth)), context.runner.cache.folder
    )
    calibration = noise_calibration(on_model(vehicle_from_dict(tomllib.loads(text)), model), log)
    switches = model_switches(text)
    if model is EstimatorModel.PAPER:
        note = "On the paper's model every `[model]` term is off: no case flips one."
    elif switches:
        count = len(switches)
        note = f"The model-fidelity terms add {count} cases (the file's `[model]` switches)."
    else:
        note = (
            "The model-fidelity terms (issue 9) are not yet in this vehicle file: no `[model]` "
            "section, so no case for them; each of its switches becomes a case when it lands."
        )
    body = "\n\n".join(
        [
            "## Ablation on the Nordschleife, method A (Table V)",
            "The plant keeps the vehicle file; the KF's copy is edited. "
            "Pooled over wheels and samples; the paper's RMSE, RMSE %, P95 and Max beside. "
            "No aero: lift 0, drag held; no ARB: bar rates 0, roll split held at the "
            "unedited file's (module docstring).",
            markdown(table),
            "**Shape.** " + compare_ranking(ours, paper, "pooled RMSE over the ablation cases"),
            "**The Rc sweep.** " + rc_words(ours, calibration),
            note,
        ]
    )
    return Section(title="Ablation", markdown=body)
