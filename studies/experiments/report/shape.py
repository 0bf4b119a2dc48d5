"""Words on where the shape of our result agrees with the paper's and where it differs.

The sentences are computed from the two sets of numbers (never written by
hand for a study): the best case of each, the order of the cases, the pairs
ordered differently (Kendall's concordance), and the level of ours against the
paper's (median ratio).
"""

from __future__ import annotations

from itertools import combinations

import numpy as np


def _order(values: dict[str, float]) -> list[str]:
    return sorted(values, key=lambda k: values[k])


def compare_ranking(ours: dict[str, float], paper: dict[str, float], what: str) -> str:
    """A paragraph comparing two sets of values (lower is better) over their common keys."""
    common = [k for k in paper if k in ours and np.isfinite(ours[k])]
    if len(common) < 2:
        return f"Too few common cases to compare {what}."
    ours = {k: ours[k] for k in common}
    paper = {k: paper[k] for k in common}
    order_ours, order_paper = _order(ours), _order(paper)
    pairs = list(combinations(common, 2))
    discordant = [
        (a, b) for a, b in pairs if np.sign(ours[a] - ours[b]) != np.sign(paper[a] - paper[b])
    ]
    ratio = float(np.median([ours[k] / paper[k] for k in common if paper[k] > 0]))
    lines = [
        f"By {what}, the paper orders {' < '.join(order_paper)}; "
        f"ours orders {' < '.join(order_ours)}."
    ]
    if order_ours[0] == order_paper[0]:
        lines.append(f"Both put {order_ours[0]} first.")
    else:
        lines.append(
            f"The best differs: {order_paper[0]} in the paper, {order_ours[0]} here "
            f"({order_paper[0]} is {order_ours.index(order_paper[0]) + 1}. of {len(common)} here)."
        )
    agree = len(pairs) - len(discordant)
    lines.append(f"{agree} of {len(pairs)} pairs are in the same order.")
    if discordant:
        shown = ", ".join(f"{a}/{b}" for a, b in discordant[:8])
        more = f" and {len(discordant) - 8} more" if len(discordant) > 8 else ""
        lines.append(f"Pairs ordered differently: {shown}{more}.")
    lines.append(f"Our values are {ratio:.2f} × the paper's (median over the cases).")
    return " ".join(lines)


def changes_from(
    ours: dict[float, float], paper: dict[float, float], base: float, what: str
) -> str:
    """A sentence: ``what`` at each key above ``base`` as a change from its value at ``base``
    [%], ours and the paper's, over their common keys."""
    keys = [k for k in paper if k in ours and k > base]
    if base not in ours or base not in paper or not keys or not ours[base] or not paper[base]:
        return f"Too few common points to compare {what}."

    def change(values, k):
        return 100.0 * (values[k] - values[base]) / values[base]

    cells = ", ".join(
        f"{change(ours, k):+.1f} % (paper {change(paper, k):+.1f} %) at {k:g}" for k in keys
    )
    return (
        f"From {base:g}, {what} ({ours[base]:.1f} N here, {paper[base]:.1f} N in the paper) "
        f"changes by {cells}."
    )
