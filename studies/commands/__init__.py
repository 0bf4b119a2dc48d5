"""Sub-commands of the ``wheelload`` console command: each one's name, the module that
registers it and its one-line summary.

``wheelload --help`` lists the commands from this table alone, importing none of the
command modules (they import CasADi, pandas, SciPy ...); each module's ``register`` gives
its sub-parser the summary written here, so the two cannot differ.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, kw_only=True)
class Command:
    """A sub-command: the module whose ``register(subparsers)`` adds it, and its summary."""

    module: str
    summary: str


_PACKAGE = "wheelload.studies.commands"

#: Every sub-command, in the order ``wheelload --help`` lists them.
CATALOG: dict[str, Command] = {
    "vehicle": Command(
        module=f"{_PACKAGE}.vehicle",
        summary="print a commented vehicle-file template, or check a vehicle file",
    ),
    "estimate": Command(
        module=f"{_PACKAGE}.estimate",
        summary="estimate the four wheel loads of a log (or many); default: the two-stage KF",
    ),
    "methods": Command(
        module=f"{_PACKAGE}.methods",
        summary="list the estimators (names for --method / --methods)",
    ),
    "compare": Command(
        module=f"{_PACKAGE}.compare",
        summary="compare estimators on a log with reference loads (paper-style table, figures)",
    ),
    "channels": Command(
        module=f"{_PACKAGE}.channels",
        summary="channel maps: a template, a log's channels, check a map on a log",
    ),
    "sensor-sets": Command(
        module=f"{_PACKAGE}.sensor_sets",
        summary="partial sensor sets and the roll-split sweep on a log",
    ),
    "bench": Command(
        module=f"{_PACKAGE}.bench.command",
        summary="timings beside their alternatives, hostile inputs, fault injection "
        "(wheelload bench --help lists them)",
    ),
    "simulate": Command(
        module=f"{_PACKAGE}.simulate",
        summary="simulate a scenario and write a log with reference loads",
    ),
    "study": Command(
        module=f"{_PACKAGE}.study",
        summary="run a comparison study and print its table",
    ),
    "codegen": Command(
        module=f"{_PACKAGE}.codegen",
        summary="generate the two-stage KF (default) or the MHE as C",
    ),
    "misra": Command(
        module=f"{_PACKAGE}.misra.command",
        summary="MISRA C:2012 findings on generated C (cppcheck), per file and rule",
    ),
    "weigh": Command(
        module=f"{_PACKAGE}.weigh",
        summary="vehicle mass and CG position from logs at rest on one or more slopes",
    ),
    "identify": Command(
        module=f"{_PACKAGE}.identify",
        summary="identify spring, damper and anti-roll-bar maps from rig data and drive logs",
    ),
    "tune": Command(
        module=f"{_PACKAGE}.tune",
        summary="fit the filter's noise densities to logs (innovation likelihood)",
    ),
    "identify-study": Command(
        module=f"{_PACKAGE}.identify_study",
        summary="identify and tune from a wrong vehicle file on plant logs; print the tables",
    ),
    "ablation": Command(
        module=f"{_PACKAGE}.ablation",
        summary="pooled RMSE / Max of the KF with each model term on and off",
    ),
    "docs": Command(
        module=f"{_PACKAGE}.docs",
        summary="build the HTML documentation site: guide, API reference, executed journeys",
    ),
}
