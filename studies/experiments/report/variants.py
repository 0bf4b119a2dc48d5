"""Which variant of each of the paper's methods the report runs (Siegloff & Choi §IV-B), and
why: paper-faithful (as the paper states it), strengthened (more than the paper's: a
stronger model or an exact constraint) or adapted (the paper does not give the method's
equations or constants; ours stand in). Set beside the tables in ``REPORT.md``."""

from __future__ import annotations

import enum
from dataclasses import dataclass

from wheelload.estimators import SuspensionModel
from wheelload.estimators.registry import method
from wheelload.studies.experiments.runs.estimator_model import EstimatorModel


class Fidelity(enum.Enum):
    PAPER_FAITHFUL = "paper-faithful"
    STRENGTHENED = "strengthened"
    ADAPTED = "adapted"


@dataclass(frozen=True, kw_only=True)
class BaselineVariant:
    """One registered method standing for one of the paper's methods A-F."""

    paper: str  # the paper's letter
    method: str  # registered name
    # A family method's with --suspension paper / full; the kf's with --model paper (every
    # [model] term and the payload estimate off) / full (the file's terms): variants_markdown
    paper_model: Fidelity
    full_model: Fidelity
    note: str


VARIANTS = (
    BaselineVariant(paper="A", method="kf", paper_model=Fidelity.PAPER_FAITHFUL,
                    full_model=Fidelity.STRENGTHENED,
                    note="§III's two-stage KF, with the project's guards and fault monitor on "
                    "either model; the full model adds the vehicle file's [model] terms (road "
                    "frame, body and unsprung inertia, links, stops, lever arm) and the online "
                    "payload estimate"),
    BaselineVariant(paper="B", method="B", paper_model=Fidelity.PAPER_FAITHFUL,
                    full_model=Fidelity.STRENGTHENED,
                    note="Alatorre's algebraic transfer with low-pass suspension pitch/roll; the "
                    "full model splits the KF's own equilibrium rows instead"),
    BaselineVariant(paper="C", method="C", paper_model=Fidelity.STRENGTHENED,
                    full_model=Fidelity.STRENGTHENED,
                    note="static loads moved onto the exact equilibrium (vertical acceleration, "
                    "lift, drag) along the suspension Jacobian, which also splits the roll "
                    "moment: far stronger than the paper's C"),
    BaselineVariant(paper="C", method="C-paper", paper_model=Fidelity.PAPER_FAITHFUL,
                    full_model=Fidelity.PAPER_FAITHFUL,
                    note="the paper's C as stated: static loads plus rigid transfer of ax, ay, "
                    "the lateral part split by the static axle loads; no vertical "
                    "acceleration, aero or suspension (the same on either model)"),
    BaselineVariant(paper="D", method="D", paper_model=Fidelity.PAPER_FAITHFUL,
                    full_model=Fidelity.STRENGTHENED,
                    note="the pseudo-measurement alone (eq. 9; the full model's with its terms)"),
    BaselineVariant(paper="E", method="E", paper_model=Fidelity.ADAPTED,
                    full_model=Fidelity.ADAPTED,
                    note="z + m_u â_u with an observer of the unsprung acceleration: Cheon's "
                    "equations are not in the papers we have"),
    BaselineVariant(paper="F", method="F", paper_model=Fidelity.ADAPTED,
                    full_model=Fidelity.ADAPTED,
                    note="Ding-style strong-tracking UKF per corner; its noise and "
                    "strong-tracking constants are the project's own (the paper gives none)"),
)  # fmt: skip


def variants_markdown(suspension: SuspensionModel, model: EstimatorModel) -> str:
    """The report's section naming each baseline's variant on the study's vehicle models: a
    family method's by ``suspension`` (``--suspension``), the kf's by ``model`` (``--model``)."""
    rows = [
        "## Which variant of each paper method runs",
        "",
        f"On the vehicle models of this run (`--model {model.value}` for the kf, "
        f"`--suspension {suspension.value}` for the others). Where our "
        "variant is stronger than the paper's, the paper-faithful one runs beside it "
        "(C-paper beside C), and the tables set both against the paper's cells.",
        "",
        "| paper | method | variant | what it is |",
        "| --- | --- | --- | --- |",
    ]
    for v in VARIANTS:
        family = method(v.method).model_choice
        paper = suspension is SuspensionModel.PAPER if family else model is EstimatorModel.PAPER
        fidelity = v.paper_model if paper else v.full_model
        rows.append(f"| {v.paper} | {v.method} | {fidelity.value} | {v.note} |")
    return "\n".join(rows) + "\n"
