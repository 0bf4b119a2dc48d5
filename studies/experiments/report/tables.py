"""Tables in the paper's layouts (Tables II-VI) as Markdown, ours beside the paper's."""

from __future__ import annotations

import numpy as np
import pandas as pd

from wheelload.models.conventions import WHEELS
from wheelload.studies.metrics import COLUMNS

UNITS = {"RMSE": "RMSE [N]", "RMSE %": "RMSE [%]", "P95": "P95 [N]", "Max": "Max [N]"}


def markdown(frame: pd.DataFrame, digits: int = 2) -> str:
    """A DataFrame as a GitHub Markdown table (index as the first columns)."""
    frame = frame.reset_index()
    head = "| " + " | ".join(str(c) for c in frame.columns) + " |"
    rule = "| " + " | ".join("---" for _ in frame.columns) + " |"

    def cell(value) -> str:
        if isinstance(value, float | np.floating):
            return "–" if not np.isfinite(value) else f"{value:.{digits}f}"
        return str(value)

    rows = ["| " + " | ".join(cell(v) for v in row) + " |" for row in frame.itertuples(False)]
    return "\n".join([head, rule, *rows])


def wheel_table(metrics: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Tables II-IV layout: rows (metric, method), columns FL FR RL RR and pooled."""
    rows = []
    for column in COLUMNS:
        for name, table in metrics.items():
            cells = {w.upper(): table.loc[w, column] for w in (*WHEELS, "pooled")}
            rows.append({"metric": UNITS[column], "method": name, **cells})
    return pd.DataFrame(rows).set_index(["metric", "method"])


def beside_paper(metrics: dict[str, pd.DataFrame], paper: pd.DataFrame) -> pd.DataFrame:
    """Each paper cell as 'ours (paper)' for the methods the paper has, per wheel; a
    paper-faithful variant ``NAME-paper`` (e.g. C-paper) beside the paper's ``NAME`` too."""
    rows = []
    for column in COLUMNS:
        for name in paper.loc[column].index:
            for ours_name in (name, f"{name}-paper"):
                if ours_name not in metrics:
                    continue
                ours = metrics[ours_name]
                cells = {
                    w.upper(): f"{ours.loc[w, column]:.2f} ({paper.loc[(column, name), w]:.2f})"
                    for w in WHEELS
                }
                rows.append({"metric": UNITS[column], "method": ours_name, **cells})
    return pd.DataFrame(rows).set_index(["metric", "method"])


def pooled_table(metrics: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """One row per case: pooled RMSE, RMSE %, P95, Max (Table V layout)."""
    rows = {name: table.loc["pooled", list(COLUMNS)] for name, table in metrics.items()}
    frame = pd.DataFrame(rows).T
    frame.index.name = "case"
    return frame.rename(columns=UNITS)
