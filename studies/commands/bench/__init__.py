"""``wheelload bench WHAT``: one front end per benchmark (``command`` holds the group).

:data:`BENCHMARKS` names each benchmark, the module whose ``register_bench(subparsers)``
adds it and its one-line summary, written here only: ``wheelload bench --help`` lists them
from this table alone, and a benchmark's module is imported only when its parser is used
(:class:`~wheelload.studies.commands.bench.command.DeferredParser`).
"""

from __future__ import annotations

from wheelload.studies.commands import Command

_HERE = "wheelload.studies.commands.bench"

#: Every benchmark, in the order ``wheelload bench --help`` lists them.
BENCHMARKS: dict[str, Command] = {
    "kf": Command(module=f"{_HERE}.kf", summary="two-stage KF: compiled run, step, numpy loop"),
    "codegen": Command(
        module=f"{_HERE}.codegen",
        summary="generated C step (double, float) against Python and filterpy",
    ),
    "speed": Command(
        module=f"{_HERE}.speed",
        summary="step vs filterpy, batched C vs single C step, C step vs its chain bound",
    ),
    "mhe": Command(module=f"{_HERE}.mhe", summary="MHE and KF time per sample, Python and C"),
    "scenarios": Command(
        module="wheelload.studies.bench.scenarios", summary="wall time of each plant scenario"
    ),
    "logs": Command(module=f"{_HERE}.logs", summary="many logs: serial, local processes, Dask"),
    "fleet": Command(
        module=f"{_HERE}.fleet",
        summary="many logs: run_batched vs the kernel, numpy and numba; 1/2 workers, Dask",
    ),
    "faults": Command(
        module="wheelload.studies.experiments.faults.fault_injection",
        summary="fault-injection table: RMSE with and without the guards, delays",
    ),
    "estimate": Command(
        module=f"{_HERE}.estimate",
        summary="wheelload estimate --out end to end (CSV vs Parquet, lean vs in-memory), "
        "cold start",
    ),
    "family": Command(
        module=f"{_HERE}.family",
        summary="every registered method's run over a log, as a ratio to the KF's",
    ),
    "hostile": Command(
        module=f"{_HERE}.hostile",
        summary="KF Python / C double / C float and MHE C on hostile inputs",
    ),
    "identify": Command(
        module=f"{_HERE}.identify",
        summary="identification: time and peak memory against log length, dense/chunked",
    ),
    "discernment": Command(
        module=f"{_HERE}.discernment",
        summary="model error, a changed car or a sensor fault: exact, loaded and wrong files",
    ),
    "recompile": Command(
        module=f"{_HERE}.recompile",
        summary="vehicle-file edit -> many-logs run: keyed by structure vs by text",
    ),
    "can": Command(
        module="wheelload.studies.bench.can_logs",
        summary="the KF on a CAN car's MDF4 and BLF logs, latency found and applied",
    ),
    "timed": Command(
        module=f"{_HERE}.timed",
        summary="C step_at: in order and a full rewind of the ring, against the step",
    ),
}
