"""Studies ``iso-dlc``, ``nordschleife``, ``hockenheim``: every registered method per wheel
(Tables II-IV), loads against reference (Fig. 5), metric bars (Fig. 6, 9, 10) and the
front-left load over a Karussell segment and a Hockenheim lap (Fig. 8).

The ISO DLC is scored over the paper's trimmed 5.0-12.0 s; the laps over the
whole lap (a short segment in --quick mode). The sensors are at the nominal
noise scale s = 1, seed 0.
"""

from __future__ import annotations

import numpy as np

from wheelload.studies.drive import tracks
from wheelload.studies.experiments.report import figures
from wheelload.studies.experiments.report.paper_numbers import PAPER_TABLES
from wheelload.studies.experiments.report.shape import compare_ranking
from wheelload.studies.experiments.report.tables import beside_paper, markdown, wheel_table
from wheelload.studies.experiments.runs.common import (
    Section,
    all_methods,
    errors_markdown,
    figure_link,
    mean_over_wheels,
    trials,
    truth_spec,
    window,
)
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.units import TrialResult, TrialSpec
from wheelload.studies.identical import collapse, identical_groups, identity_notes

TITLES = {
    "iso-dlc": "ISO double lane change, trimmed 5.0-12.0 s (Table II, Figs. 5-6)",
    "nordschleife": "Nürburgring Nordschleife lap (Table III, Figs. 8a, 9)",
    "hockenheim": "Hockenheim lap (Table IV, Figs. 8b, 10)",
}
FIG8_METHODS = ("kf", "B", "C", "E")  # the methods the paper's Fig. 8 shows
KARUSSELL_SPAN = 300.0  # m of road shown around the Karussell's apex


def headline_result(context: Context, scenario: str) -> TrialResult:
    """Every method on ``scenario`` at s = 1, seed 0, loads kept for the figures."""
    spec = TrialSpec(
        truth=truth_spec(context, scenario),
        vehicle_text=context.settings.vehicle_text,
        methods=all_methods(),
        window=window(scenario),
        keep_estimates=True,
    )
    return trials(context, [spec], scenario)[0]


def karussell_apex() -> float:
    """Distance [m] of the Karussell: the middle of the 200 m of the Nordschleife that turn
    most to the left (the Caracciola-Karussell turns about 210° within 200 m; 212° at
    14.17 km of the bundled centre line, no other bend comes close)."""
    road = tracks.nordschleife()
    s, heading = np.asarray(road.s), np.unwrap(np.asarray(road.heading))
    n = int(round(200.0 / (s[1] - s[0])))
    turn, middle = heading[n:] - heading[:-n], s[:-n] + 100.0
    lap = (middle > 0.0) & (middle < road.length)
    return float(middle[lap][np.argmax(turn[lap])])


def _fig8_panel(scenario: str, result: TrialResult) -> tuple:
    estimates = {k: v for k, v in (result.estimates or {}).items() if k in FIG8_METHODS}
    if scenario == "hockenheim":
        return ("(b) Hockenheim lap", result.s, result.reference, estimates)
    apex = karussell_apex()
    near = np.abs(result.s - apex) <= KARUSSELL_SPAN / 2
    if not near.any():
        title = (
            f"(a) Nordschleife, first {result.s[-1]:.0f} m (--quick: the Karussell at "
            f"{apex:.0f} m is not driven)"
        )
        return (title, result.s, result.reference, estimates)
    title = f"(a) Karussell segment, s = {apex - 150:.0f}-{apex + 150:.0f} m"
    chosen = {k: v[near] for k, v in estimates.items()}
    return (title, result.s[near], result.reference[near], chosen)


def faithful_c_ranking(ours: dict[str, float], paper: dict[str, float]) -> list[str]:
    """The RMSE ranking again with the paper-faithful C-paper in C's place (none without it)."""
    if "C-paper" not in ours:
        return []
    swapped = {**ours, "C": ours["C-paper"]}
    return [
        "With C-paper in C's place: " + compare_ranking(swapped, paper, "RMSE averaged over wheels")
    ]


def run(context: Context, scenario: str) -> Section:
    """Write the table (CSV, Markdown) and figures of ``scenario``; the report section."""
    result = headline_result(context, scenario)
    out = context.outputs
    # Identical methods once in the table and the figures (studies/identical.py).
    loads = result.estimates or {}
    groups = identical_groups(loads)
    metrics, notes = collapse(result.metrics, groups), identity_notes(loads, groups)
    table = wheel_table(metrics)
    out.write_text(f"{scenario}_table.csv", table.to_csv(float_format="%.3f"))
    bars = figures.metric_bars(metrics, TITLES[scenario], notes)
    bars_name = out.save_figure(bars, f"{scenario}_metrics.png").name
    figures.close(bars)
    links = [figure_link(bars_name, f"{scenario} metric bars")]
    if scenario == "iso-dlc":
        estimates = collapse(loads, groups)
        fig = figures.loads_figure(result.t, result.reference, estimates, TITLES[scenario], notes)
        links.insert(0, figure_link(out.save_figure(fig, "iso-dlc_loads.png").name, "Fig. 5"))
        figures.close(fig)
    else:
        fig = figures.front_left_panels([_fig8_panel(scenario, result)], "s [m]")
        name = "nordschleife_karussell.png" if scenario == "nordschleife" else "hockenheim_lap.png"
        links.append(figure_link(out.save_figure(fig, name).name, "Fig. 8"))
        figures.close(fig)
    label, paper = PAPER_TABLES[scenario]
    ours_rmse = {k: mean_over_wheels(v, "RMSE") for k, v in result.metrics.items()}
    ours_max = {k: mean_over_wheels(v, "Max") for k, v in result.metrics.items()}
    paper_rmse = {m: float(paper.loc[("RMSE", m)].mean()) for m in paper.loc["RMSE"].index}
    paper_max = {m: float(paper.loc[("Max", m)].mean()) for m in paper.loc["Max"].index}
    text = "\n\n".join(
        [
            f"## {TITLES[scenario]}",
            f"{len(result.t)} samples scored. Every registered method, per wheel and pooled:",
            markdown(table),
            *(f"*Note:* {note}." for note in notes),
            f"Ours on the vehicle **{context.settings.vehicle_name}** beside the paper's {label} "
            "(the paper's Table I sports car): each cell is ours (paper), methods A-F = "
            "kf, B, C, D, E, F; C-paper (the paper's C as stated) beside the paper's C too.",
            markdown(beside_paper(result.metrics, paper)),
            "**Shape.** " + compare_ranking(ours_rmse, paper_rmse, "RMSE averaged over wheels"),
            compare_ranking(ours_max, paper_max, "Max averaged over wheels"),
            *faithful_c_ranking(ours_rmse, paper_rmse),
            *links,
        ]
    )
    return Section(title=TITLES[scenario], markdown=text + errors_markdown(result))
