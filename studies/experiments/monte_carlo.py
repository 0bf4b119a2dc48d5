"""Study ``monte-carlo`` (Table VI): the KF on one simulated Nordschleife lap measured with the
sensor models at noise scale s in {0, 0.5, 1, 2, 4, 8, 16}, independent seeds per trial
(paper §IV-F); the mean and sample standard deviation of the pooled metrics per scale.

Three variants (:class:`~wheelload.studies.drive.sensors.NoiseScaling`, whose docstring
quotes the paper's sentences), on the same seeds: s multiplies the accelerometers' and
travel sensors' errors random in time (white noise, bias walk, repeatability;
``PAPER_STOCHASTIC``), or all their listed components (also turn-on bias, linearity,
logger step; ``PAPER_SENSORS``), every other sensor at its nominal errors; or every
sensor's errors (``ALL``). The trials'
logs are filtered side by side in the generated library's batched step.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from wheelload.studies.drive.sensors import NoiseScaling
from wheelload.studies.experiments.report.paper_numbers import MONTE_CARLO
from wheelload.studies.experiments.report.shape import changes_from
from wheelload.studies.experiments.report.tables import markdown
from wheelload.studies.experiments.runs.common import Section, kf_trials, truth_spec
from wheelload.studies.experiments.runs.context import QUICK_TRIALS, Context
from wheelload.studies.experiments.runs.units import TrialSpec

SCALES = (0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
TRIALS = 30
FIRST_SEED = 1000  # trial i measures with seed FIRST_SEED + i (seed 0 is the headline run)
VARIANTS = (NoiseScaling.PAPER_STOCHASTIC, NoiseScaling.PAPER_SENSORS, NoiseScaling.ALL)
LABELS = {
    NoiseScaling.PAPER_STOCHASTIC: "paper, random parts",
    NoiseScaling.PAPER_SENSORS: "paper, all parts",
    NoiseScaling.ALL: "every error",
}
METRICS = ("RMSE", "P95", "Max")


def scale_table(trials_frame: pd.DataFrame) -> pd.DataFrame:
    """Per variant and scale: μ and σ (sample, ddof 1) of the pooled RMSE, P95, Max [N]."""
    grouped = trials_frame.groupby(["variant", "s"])[list(METRICS)]
    mean, std = grouped.mean(), grouped.std(ddof=1).fillna(0.0)
    columns = {}
    for metric in METRICS:
        columns[f"{metric} μ"] = mean[metric]
        columns[f"{metric} σ"] = std[metric]
    return pd.DataFrame(columns)


def side_by_side(table: pd.DataFrame) -> pd.DataFrame:
    """Scale × (paper, each variant) cells 'μ ± σ' of the pooled RMSE, P95 and Max [N]."""
    rows = []
    for s in SCALES:
        paper = MONTE_CARLO[s]
        row = {"s": s}
        for i, metric in enumerate(METRICS):
            row[f"paper {metric}"] = f"{paper[2 * i]:.1f} ± {paper[2 * i + 1]:.2f}"
            for variant in VARIANTS:
                if (variant.value, s) in table.index:
                    cell = table.loc[(variant.value, s)]
                    mu, sigma = cell[f"{metric} μ"], cell[f"{metric} σ"]
                    row[f"{LABELS[variant]} {metric}"] = f"{mu:.1f} ± {sigma:.2f}"
        rows.append(row)
    return pd.DataFrame(rows).set_index("s")


def trend_words(table: pd.DataFrame) -> str:
    """Sentences on the mean and σ of the pooled RMSE against the paper's, from s = 1."""
    paper_mean = {s: v[0] for s, v in MONTE_CARLO.items()}
    paper_std = {s: v[1] for s, v in MONTE_CARLO.items()}
    lines = []
    for variant in VARIANTS:
        part = table.loc[variant.value]
        mean = dict(zip(part.index, part["RMSE μ"]))
        std = dict(zip(part.index, part["RMSE σ"]))
        label = LABELS[variant]
        lines.append(f"*{label}*: " + changes_from(mean, paper_mean, 1.0, "the mean pooled RMSE"))
        positive = [s for s in SCALES[1:] if s in std]
        monotone = bool(np.all(np.diff([std[s] for s in positive]) >= 0.0))
        lines.append(
            f"Its trial-to-trial σ is {std.get(1.0, np.nan):.2f} N at s = 1 and "
            f"{std.get(16.0, np.nan):.2f} N at s = 16 (paper {paper_std[1.0]:.2f} and "
            f"{paper_std[16.0]:.2f} N) and {'rises' if monotone else 'does not rise'} "
            "monotonically with s (the paper's does)."
        )
    return " ".join(lines)


def run(context: Context) -> Section:
    truth = truth_spec(context, "nordschleife")
    count = QUICK_TRIALS if context.settings.quick else TRIALS
    cases = [(v, s, FIRST_SEED + i) for v in VARIANTS for s in SCALES for i in range(count)]
    specs = [
        TrialSpec(
            truth=truth,
            vehicle_text=context.settings.vehicle_text,
            methods=("kf",),
            noise=s,
            scaling=variant,
            seed=seed,
        )  # fmt: skip
        for variant, s, seed in cases
    ]
    results = kf_trials(context, specs, "monte-carlo")  # side by side in the batched C
    rows = []
    for (variant, s, seed), result in zip(cases, results):
        pooled = result.metrics["kf"].loc["pooled"]
        rows.append({"variant": variant.value, "s": s, "seed": seed, "RMSE": pooled["RMSE"],
                     "P95": pooled["P95"], "Max": pooled["Max"]})  # fmt: skip
    trials_frame = pd.DataFrame(rows)
    context.outputs.write_text("monte-carlo_trials.csv", trials_frame.to_csv(index=False))
    table = scale_table(trials_frame)
    context.outputs.write_text("monte-carlo_table.csv", table.to_csv(float_format="%.3f"))
    body = "\n\n".join(
        [
            f"## Monte Carlo noise scaling (Table VI), {count} trials per scale",
            "Pooled over wheels and samples, μ ± σ over the trials [N]. s reaches what §IV-F "
            "perturbs, the accelerometers and travel sensors, the gyroscopes, hub "
            "accelerometers and speed at their nominal errors: *paper, random parts*: their "
            "errors random in time (white noise, bias walk, repeatability); *paper, all "
            "parts*: also the turn-on bias, the linearity curve and the logger step; *every "
            "error*: s multiplies every sensor's errors. Same seeds in all three.",
            markdown(side_by_side(table)),
            "**Trend.** " + trend_words(table),
        ]
    )
    return Section(title="Monte Carlo", markdown=body)
