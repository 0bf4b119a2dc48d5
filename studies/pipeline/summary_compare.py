"""Two summary tables of many logs compared: the same bit for bit, within tolerance, or not.

``same``: equal bit for bit; ``within``: the same shape, columns and text, every
number within :data:`~wheelload.studies.pipeline.batch.BATCHED_TOLERANCE` relative
to its column's largest magnitude; ``NO`` otherwise.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from wheelload.studies.pipeline.batch import BATCHED_TOLERANCE


def compare(table: pd.DataFrame, reference: pd.DataFrame) -> tuple[str, float]:
    """``same``, ``within`` or ``NO`` (module docstring) and the largest difference of the
    numbers (inf when the tables differ in shape, columns or text)."""
    if table.equals(reference):
        return "same", 0.0
    numbers = reference.select_dtypes("number").columns
    text = [c for c in reference.columns if c not in numbers]
    if list(table.columns) != list(reference.columns) or len(table) != len(reference):
        return "NO", float("inf")
    if not table[text].equals(reference[text]):
        return "NO", float("inf")
    a, b = table[numbers].to_numpy(float), reference[numbers].to_numpy(float)
    if not np.array_equal(np.isnan(a), np.isnan(b)):
        return "NO", float("inf")
    difference = np.abs(np.nan_to_num(a - b))
    scale = np.nanmax(np.abs(b), axis=0, initial=0.0)
    within = (difference <= BATCHED_TOLERANCE * scale).all()
    return ("within" if within else "NO"), float(difference.max(initial=0.0))
