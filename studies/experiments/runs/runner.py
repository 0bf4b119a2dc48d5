"""The shared runner of the studies: cached units of work, run serially, on local
processes or on an existing Dask cluster, with a progress bar.

A :class:`Job` is a top-level function, its frozen settings and a kind; its
result is cached under :func:`~wheelload.studies.experiments.runs.cache.cache_key`
so a rerun computes only the jobs whose inputs (or the code) changed.
:attr:`Runner.computed` and :attr:`Runner.cached` count what each run did.

Example
-------
>>> runner = Runner(cache=ResultCache(folder=Path("out/.cache")), workers=2)
>>> frames = runner.run([Job(kind="truth", function=simulate_truth, spec=spec)], "simulate")
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tqdm import tqdm

from wheelload.studies.experiments.runs.cache import MISSING, ResultCache, cache_key
from wheelload.studies.workers import ignore_interrupts


@dataclass(frozen=True, kw_only=True)
class Job:
    """One unit of work: ``function(spec, cache_folder)``; ``kind`` names it in the key."""

    kind: str
    function: Callable[[Any, Path], Any]
    spec: Any

    def key(self) -> str:
        return cache_key(self.kind, self.spec)


def _execute(job: Job, folder: Path) -> Any:
    return job.function(job.spec, folder)


@dataclass(kw_only=True)
class Runner:
    """Runs jobs through the cache; ``workers`` local processes (1: in this process) or
    the Dask scheduler at ``dask_address`` (its workers must see ``cache.folder``)."""

    cache: ResultCache
    workers: int = 1
    dask_address: str | None = None
    progress: bool = True
    computed: int = field(default=0, init=False)
    cached: int = field(default=0, init=False)
    _pool: ProcessPoolExecutor | None = field(default=None, init=False, repr=False)
    _client: Any = field(default=None, init=False, repr=False)

    def __enter__(self) -> Runner:
        return self

    def __exit__(self, *_exc) -> None:
        self.close()

    def close(self) -> None:
        """Stop the local processes and the Dask client (kept between :meth:`run` calls, so
        their imports and compiled methods are paid once per study command)."""
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)  # on Ctrl-C: no job left to start
            self._pool = None
        if self._client is not None:
            self._client.close()
            self._client = None

    def run(self, jobs: list[Job], label: str) -> list[Any]:
        """The results of ``jobs`` in order; only jobs not in the cache are computed."""
        keys = [job.key() for job in jobs]
        todo: dict[str, Job] = {}
        values: dict[str, Any] = {}
        for key, job in zip(keys, jobs):
            if key in todo or key in values:
                continue
            value = self.cache.get(key)  # a bad entry is MISSING (with a note): computed again
            if value is MISSING:
                todo[key] = job
            else:
                values[key] = value
        self.cached += len(values)
        if todo:
            with tqdm(total=len(todo), desc=label, disable=not self.progress, unit="job") as bar:
                for key, value in self._compute(todo):
                    self.cache.store(key, value)
                    values[key] = value
                    self.computed += 1
                    bar.update(1)
        return [values[key] for key in keys]

    def _compute(self, todo: dict[str, Job]):
        folder = Path(self.cache.folder)
        if self.dask_address is not None:
            yield from self._dask(todo, folder)
        elif self.workers <= 1 or len(todo) == 1:
            for key, job in todo.items():
                yield key, _execute(job, folder)
        else:
            if self._pool is None:
                context = multiprocessing.get_context("forkserver")
                self._pool = ProcessPoolExecutor(
                    max_workers=self.workers, mp_context=context, initializer=ignore_interrupts
                )
            futures = {self._pool.submit(_execute, job, folder): key for key, job in todo.items()}
            for future in as_completed(futures):
                yield futures[future], future.result()

    def _dask(self, todo: dict[str, Job], folder: Path):
        from distributed import Client
        from distributed import as_completed as dask_completed

        if self._client is None:
            self._client = Client(self.dask_address)
        futures = {
            self._client.submit(_execute, job, folder, key=f"wheelload-{key}"): key
            for key, job in todo.items()
        }
        for future in dask_completed(list(futures)):
            yield futures[future], future.result()


def check_scheduler(address: str) -> None:
    """A one-line error when no Dask scheduler answers at ``address``."""
    from distributed import Client

    try:
        Client(address, timeout=10).close()
    except (OSError, TimeoutError, ValueError) as error:
        raise ValueError(
            f"--dask {address}: no Dask scheduler answers ({type(error).__name__}); "
            "start one (dask scheduler) or give its address as tcp://HOST:PORT"
        ) from None
