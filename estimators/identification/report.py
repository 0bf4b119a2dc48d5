"""Tables of an identification: parameters (value, standard error, change), fit RMSE, correlation.

``parameter_table`` and ``rmse_table`` are the CSV files of the report;
``markdown_report`` is its readable form; ``file_changes`` gives the vehicle
file keys to change, each with a comment stating the standard error and the
data it came from.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators.identification.file_keys import Key, key_text
from wheelload.estimators.identification.fit import Identification
from wheelload.estimators.identification.model import base_parameter, segment_index


def parameter_table(result: Identification, keys: dict[str, Key]) -> pd.DataFrame:
    """One row per fitted or held parameter the data can see."""
    rows = []
    for j, name in enumerate(result.names):
        fitted = j in result.free
        if not fitted and name not in result.held:
            continue
        base = base_parameter(name)
        key = keys[base] if base in keys and segment_index(name) in (None, 0) else None
        initial, value = result.initial[j], result.value[j]
        rows.append(
            {
                "parameter": name,
                "file_key": key_text(key) if key else "",
                "input": initial,
                "value": value,
                "std_error": result.std_error[j],
                "change_pct": 100.0 * (value - initial) / initial if initial else np.nan,
                "status": "identified" if fitted else result.held[name],
                "sources": "; ".join(result.sources[name]) if name in result.sources else "",
            }
        )
    return pd.DataFrame(rows)


def rmse_table(result: Identification) -> pd.DataFrame:
    """Fit RMSE [N] per data set and wheel, with the residual scale and autocorrelation."""
    rows = []
    for (label, wheel), rmse in result.rmse().items():
        g = [data.label() for data in result.sets].index(label)
        rows.append(
            {
                "data": label,
                "kind": result.sets[g].kind.value,
                "wheel": wheel,
                "rmse": rmse,
                "robust_scale": result.scale[g],
                "lag1_autocorrelation": result.autocorrelation[g],
            }
        )
    return pd.DataFrame(rows)


def correlation_table(result: Identification) -> pd.DataFrame:
    names = [result.names[j] for j in result.free]
    return pd.DataFrame(result.correlation, index=names, columns=names)


def file_changes(result: Identification, keys: dict[str, Key]) -> dict[Key, tuple[float, str]]:
    """Vehicle-file keys to write: identified values with standard error and sources.

    A piecewise map's first segment (the low-velocity slope of the paper's
    eq. 5) goes to the linear key; the other segments are in the report.
    """
    changes = {}
    for j in result.free:
        name = result.names[j]
        if segment_index(name) not in (None, 0) or base_parameter(name) not in keys:
            continue
        sources = ", ".join(result.sources[name]) if name in result.sources else "data"
        what = ""
        if segment_index(name) == 0:
            stem = base_parameter(name)
            slopes = [
                f"{result.value[k]:.5g}"
                for k, other in enumerate(result.names)
                if segment_index(other) is not None and base_parameter(other) == stem
            ]
            what = f"low-velocity slope of the fitted map (segment slopes {', '.join(slopes)}), "
        comment = (
            f"identified: {what}± {result.std_error[j]:.4g} (1σ) from {sources}; "
            f"input {result.initial[j]:.6g}"
        )
        changes[keys[base_parameter(name)]] = (float(result.value[j]), comment)
    return changes


def _markdown(frame: pd.DataFrame, digits: int = 4) -> str:
    header = "| " + " | ".join(map(str, frame.columns)) + " |"
    rule = "|" + "---|" * len(frame.columns)
    lines = [header, rule]
    for _, row in frame.iterrows():
        cells = [
            f"{value:.{digits}g}" if isinstance(value, float | np.floating) else str(value)
            for value in row
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def markdown_report(
    result: Identification,
    keys: dict[str, Key],
    *,
    vehicle: str,
    output: str,
    figures: tuple[str, ...] = (),
) -> str:
    """The report as Markdown."""
    params = parameter_table(result, keys)
    lines = [
        "# Suspension identification",
        "",
        f"Input vehicle file: `{vehicle}`; identified file: `{output}`; loss: {result.loss.value}.",
        "",
        "Data: "
        + ", ".join(f"{d.label()} ({d.kind.value}, {len(d)} samples)" for d in result.sets),
        "",
        "## Parameters",
        "",
        _markdown(params),
        "",
        "Standard errors are 1σ, from the fit residuals with the lag-one "
        "autocorrelation of each data set taken into account (AR(1) effective sample size).",
        "",
    ]
    if result.warnings:
        lines += ["## Warnings", ""] + [f"- {w}" for w in result.warnings] + [""]
    lines += ["## Fit RMSE per data set and wheel", "", _markdown(rmse_table(result)), ""]
    if result.free:
        corr = correlation_table(result).reset_index(names="")
        lines += ["## Parameter correlation", "", _markdown(corr, 2), ""]
    if figures:
        lines += ["## Figures", ""] + [f"![{Path(f).stem}]({Path(f).name})" for f in figures]
    return "\n".join(lines) + "\n"
