"""Study ``monte-carlo`` (Table VI): the KF on one simulated Nordschleife lap measured with the
sensor models at noise scale s in {0, 0.5, 1, 2, 4, 8, 16}, independent seeds per trial
(paper §IV-F); the mean and sample standard deviation of the pooled metrics per scale. The
trials' logs are filtered side by side in the generated library's batched step."""

from __future__ import annotations

import numpy as np
import pandas as pd

from wheelload.studies.experiments.report.paper_numbers import MONTE_CARLO
from wheelload.studies.experiments.report.shape import compare_trend
from wheelload.studies.experiments.report.tables import markdown
from wheelload.studies.experiments.runs.common import Section, kf_trials, truth_spec
from wheelload.studies.experiments.runs.context import QUICK_TRIALS, Context
from wheelload.studies.experiments.runs.units import TrialSpec

SCALES = (0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
TRIALS = 30
FIRST_SEED = 1000  # trial i measures with seed FIRST_SEED + i (seed 0 is the headline run)


def run(context: Context) -> Section:
    truth = truth_spec(context, "nordschleife")
    count = QUICK_TRIALS if context.settings.quick else TRIALS
    cases = [(s, FIRST_SEED + i) for s in SCALES for i in range(count)]
    specs = [
        TrialSpec(
            truth=truth,
            vehicle_text=context.settings.vehicle_text,
            methods=("kf",),
            noise=s,
            seed=seed,
        )  # fmt: skip
        for s, seed in cases
    ]
    results = kf_trials(context, specs, "monte-carlo")  # side by side in the batched C
    rows = []
    for (s, seed), result in zip(cases, results):
        pooled = result.metrics["kf"].loc["pooled"]
        rows.append({"s": s, "seed": seed, "RMSE": pooled["RMSE"], "P95": pooled["P95"],
                     "Max": pooled["Max"]})  # fmt: skip
    trials_frame = pd.DataFrame(rows)
    context.outputs.write_text("monte-carlo_trials.csv", trials_frame.to_csv(index=False))
    grouped = trials_frame.groupby("s")[["RMSE", "P95", "Max"]]
    mean, std = grouped.mean(), grouped.std(ddof=1).fillna(0.0)
    table = pd.DataFrame(
        {
            "RMSE μ [N]": mean["RMSE"],
            "RMSE σ [N]": std["RMSE"],
            "P95 μ [N]": mean["P95"],
            "P95 σ [N]": std["P95"],
            "Max μ [N]": mean["Max"],
            "Max σ [N]": std["Max"],
            "paper RMSE μ": [MONTE_CARLO[s][0] for s in mean.index],
            "paper RMSE σ": [MONTE_CARLO[s][1] for s in mean.index],
            "paper P95 μ": [MONTE_CARLO[s][2] for s in mean.index],
        }
    )
    context.outputs.write_text("monte-carlo_table.csv", table.to_csv(float_format="%.3f"))
    ours_mean = dict(zip(mean.index, mean["RMSE"]))
    ours_std = dict(zip(std.index, std["RMSE"]))
    paper_mean = {s: v[0] for s, v in MONTE_CARLO.items()}
    paper_std = {s: v[1] for s, v in MONTE_CARLO.items()}
    monotone = bool(np.all(np.diff([ours_std[s] for s in SCALES[1:]]) >= 0.0))
    body = "\n\n".join(
        [
            f"## Monte Carlo noise scaling (Table VI), {count} trials per scale",
            markdown(table.reset_index().set_index("s"), digits=2),
            "**Shape.** " + compare_trend(ours_mean, paper_mean, "The mean pooled RMSE")
            + " " + compare_trend(
                {k: v for k, v in ours_std.items() if k > 0},
                {k: v for k, v in paper_std.items() if k > 0},
                "Its trial-to-trial σ",
            )
            + f" The σ {'rises' if monotone else 'does not rise'} monotonically with s here"
            " (the paper's does).",
        ]
    )  # fmt: skip
    return Section(title="Monte Carlo", markdown=body)
