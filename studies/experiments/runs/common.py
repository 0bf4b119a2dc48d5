"""Helpers shared by the studies: jobs for a scenario, merged results, report sections."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from wheelload.estimators import DEFAULT_MODEL, SuspensionModel
from wheelload.estimators.registry import method, methods
from wheelload.models.conventions import WHEELS
from wheelload.studies.experiments.runs.cache import cache_key
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.runner import Job
from wheelload.studies.experiments.runs.units import (
    KF_TRIALS,
    TRIAL,
    TRUTH,
    KfTrials,
    TrialResult,
    TrialSpec,
    TruthSpec,
    run_kf_trials,
    run_trial,
    simulate_truth,
)

ISO_DLC_WINDOW = (5.0, 12.0)  # s, the paper's trimmed manoeuvre (§IV-C)


@dataclass(frozen=True, kw_only=True)
class Section:
    """One study's part of the report (Markdown, figures linked by file name)."""

    title: str
    markdown: str


def all_methods() -> tuple[str, ...]:
    """Every registered method, in the registry's order."""
    return tuple(methods())


def truth_spec(context: Context, scenario: str, vehicle_text: str | None = None) -> TruthSpec:
    """The plant run of ``scenario`` (a short segment in --quick mode; iso-dlc is whole)."""
    settings = context.settings
    shorten = 1.0 if scenario == "iso-dlc" else settings.shorten
    text = settings.vehicle_text if vehicle_text is None else vehicle_text
    return TruthSpec(scenario=scenario, vehicle_text=text, shorten=shorten)


def window(scenario: str) -> tuple[float, float] | None:
    return ISO_DLC_WINDOW if scenario == "iso-dlc" else None


def simulate(context: Context, truths: list[TruthSpec]) -> None:
    """Run (or find in the cache) the plant runs the trials need."""
    jobs = [Job(kind=TRUTH, function=simulate_truth, spec=spec) for spec in truths]
    context.runner.run(jobs, "simulate")


def trials(context: Context, specs: list[TrialSpec], label: str) -> list[TrialResult]:
    """Simulate what the trials need, then run them one job per method; merged per spec.

    Every trial runs the family methods on the study's vehicle model
    (:attr:`~wheelload.studies.experiments.runs.context.Settings.suspension`); a method
    without that choice keeps the default, so its cached result serves either model. Every
    method is built on the study's estimators' model
    (:attr:`~wheelload.studies.experiments.runs.context.Settings.model`).
    """
    simulate(context, list(dict.fromkeys(spec.truth for spec in specs)))
    jobs, owners = [], []
    for i, spec in enumerate(specs):
        truth_key = cache_key(TRUTH, spec.truth)
        for name in spec.methods:
            single = replace(
                spec,
                methods=(name,),
                truth_key=truth_key,
                suspension=_model(name, context),
                model=context.settings.model,
            )
            jobs.append(Job(kind=TRIAL, function=run_trial, spec=single))
            owners.append(i)
    parts = context.runner.run(jobs, label)
    merged: list[list[TrialResult]] = [[] for _ in specs]
    for owner, part in zip(owners, parts):
        merged[owner].append(part)
    return [merge(group) for group in merged]


def _model(name: str, context: Context) -> SuspensionModel:
    """The study's vehicle model for a family method; the default for a core one."""
    return context.settings.suspension if method(name).model_choice else DEFAULT_MODEL


#: KF trials filtered side by side per unit of work (:func:`kf_trials`).
KF_BATCH = 16


def kf_trials(context: Context, specs: list[TrialSpec], label: str) -> list[TrialResult]:
    """As :func:`trials` for specs of the KF alone (one vehicle file), :data:`KF_BATCH`
    measured logs per unit of work stepped side by side in the generated C, on the study's
    estimators' model."""
    simulate(context, list(dict.fromkeys(spec.truth for spec in specs)))
    model = context.settings.model
    keyed = [replace(spec, truth_key=cache_key(TRUTH, spec.truth), model=model) for spec in specs]
    batches = [tuple(keyed[i : i + KF_BATCH]) for i in range(0, len(keyed), KF_BATCH)]
    jobs = [Job(kind=KF_TRIALS, function=run_kf_trials, spec=KfTrials(specs=batch))
            for batch in batches]  # fmt: skip
    return [result for part in context.runner.run(jobs, label) for result in part]


def merge(parts: list[TrialResult]) -> TrialResult:
    """One result from per-method results of the same measured log."""
    first = parts[0]
    estimates = None
    if first.estimates is not None:
        estimates = {k: v for p in parts for k, v in (p.estimates or {}).items()}
    masses = None
    if first.mass_properties is not None:
        masses = {k: v for p in parts for k, v in (p.mass_properties or {}).items()}
    return TrialResult(
        metrics={k: v for p in parts for k, v in p.metrics.items()},
        errors={k: v for p in parts for k, v in p.errors.items()},
        seconds_per_sample={k: v for p in parts for k, v in p.seconds_per_sample.items()},
        t=first.t,
        s=first.s,
        reference=first.reference,
        estimates=estimates,
        mass_properties=masses,
    )


def pooled(result: TrialResult, column: str) -> dict[str, float]:
    """Pooled ``column`` per method."""
    return {name: float(table.loc["pooled", column]) for name, table in result.metrics.items()}


def mean_over_wheels(table: pd.DataFrame, column: str) -> float:
    return float(np.mean([table.loc[w, column] for w in WHEELS]))


def errors_markdown(result: TrialResult) -> str:
    if not result.errors:
        return ""
    lines = [f"- `{name}` failed: {text}" for name, text in result.errors.items()]
    return "\n\nMethods that failed (no row):\n\n" + "\n".join(lines)


def figure_link(name: str, caption: str) -> str:
    return f"![{caption}]({name})"
