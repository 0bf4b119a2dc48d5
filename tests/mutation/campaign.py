"""A mutation campaign: one mistake at a time, each run against the tests of its area.

Run from a checkout (the tests are not installed)::

    python3 tests/mutation/campaign.py --sample 60 --workers 2 --out mutation.md

For each area (:data:`AREAS`) the mutants of its modules (:mod:`mutants`) are drawn at
random with a fixed seed, together with the hand-made mistakes of :data:`NAMED`; each
is written into a private copy of the checkout and the area's tests run against it
(``pytest -x``): a mutant is *killed* when a test fails or the tests cannot import it,
*survives* when every test passes, and times out after ``--timeout-factor`` times the
unmutated run (a hang is a kill). The table (mutant, file:line, before -> after, which
test killed it) and the score per area are printed and written to ``--out``. Mutants in
:data:`EQUIVALENT` compute the same numbers as the original (a written reason each):
they are run and listed but left out of the score.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from mutants import Mutant, mutants  # this folder: the script's own

ROOT = Path(__file__).resolve().parent.parent.parent


@dataclass(frozen=True)
class Area:
    """Modules mutated together and the tests that mirror them."""

    modules: tuple[str, ...]  # globs below the checkout
    tests: tuple[str, ...]
    exclude: tuple[str, ...] = ()

    def files(self) -> list[str]:
        found = set()
        for pattern in self.modules:
            found.update(str(p.relative_to(ROOT)) for p in ROOT.glob(pattern))
        excluded = set()
        for pattern in self.exclude:
            excluded.update(str(p.relative_to(ROOT)) for p in ROOT.glob(pattern))
        return sorted(f for f in found - excluded if not f.endswith("__init__.py"))


#: The areas where a mistake hurts users most. ``models/files`` (the build cache) is the
#: runtime, not physics: its own tests cover it and it is not scored here.
AREAS = {
    "models": Area(
        ("models/**/*.py",),
        (
            "tests/models/test_models.py",
            "tests/models/suspension/test_suspension.py",
            "tests/models/test_model_terms.py",
            "tests/estimators/family",
            "tests/models/plant",
            "tests/equivalence",
            "tests/models",
        ),
        exclude=("models/runtime/*.py",),
    ),
    "kf-step": Area(
        (
            "estimators/kf/step.py",
            "estimators/guards/limits.py",
            "estimators/guards/innovation_gate.py",
            "estimators/kf/projection.py",
            "estimators/kf/payload.py",
            "estimators/guards/plausibility.py",
            "estimators/kf/reported_std.py",
        ),
        ("tests/estimators/kf",),
    ),  # fmt: skip
    "readers": Area(
        ("estimators/logs/readers/*.py",),
        ("tests/estimators/logs", "tests/robustness/test_robustness_readers.py"),
    ),
    "tyre-step": Area(
        ("estimators/family/tyres/*.py", "models/family/tyre_forces.py"),
        ("tests/estimators/family/tyres/test_tyre_forces.py",),
    ),
}


def _named(area: str, path: str, before: str, after: str) -> tuple[str, Mutant]:
    """A hand-made mistake: the first ``before`` in ``path`` becomes ``after``."""
    source = (ROOT / path).read_text()
    start = source.index(before)
    end = start + len(before)

    def place(at):  # (line, UTF-8 byte column) of a character offset
        line_start = source.rfind("\n", 0, at) + 1
        return source.count("\n", 0, at) + 1, len(source[line_start:at].encode())

    return area, Mutant(path, *place(start), *place(end), "named", before, after)


def named_mutants() -> list[tuple[str, Mutant]]:
    """The mistakes a hand campaign found the suite blind to (issue 45), kept as regressions."""
    return [
        _named("models", "models/suspension/elements.py",
               "eta = ratio * (d_left - d_right)", "eta = ratio**2 * (d_left - d_right)"),
        _named("readers", "estimators/logs/readers/units.py",
               '"mph": (Kind.SPEED, 0.44704)', '"mph": (Kind.SPEED, 1.609)'),
        _named("tyre-step", "models/family/tyre_forces.py",
               "fxf * c + fxr, fxf * s,", "fxf * c + fxr, -fxf * s,"),
        _named("kf-step", "estimators/guards/limits.py",
               "ca.fabs(x[i]) <= g.load_limit * weight", "x[i] <= g.load_limit * weight"),
        _named("kf-step", "estimators/guards/limits.py",
               "ca.sqrt(ceiling / P[i, i])", "(ceiling / P[i, i])"),
        _named("kf-step", "estimators/guards/innovation_gate.py",
               "count_prior >= 3", "count_prior >= 4"),
        _named("kf-step", "estimators/kf/projection.py",
               "P if weighting is Weighting.MAXIMUM_PROBABILITY else ca.DM.eye(x.shape[0])",
               "ca.DM.eye(x.shape[0]) if weighting is Weighting.MAXIMUM_PROBABILITY else P"),
        _named("kf-step", "estimators/kf/payload.py",
               "J = ca.vertcat(J[0, :], ca.horzcat(ca.DM.zeros(2, 1), J[1:3, 1:]))",
               "J = ca.vertcat(J[0, :], J[1:3, :])"),
    ]  # fmt: skip


#: Mutants that compute the same numbers as the original, by (file:line, after): why.
EQUIVALENT: dict[tuple[str, str], str] = {
    ("models/parameters.py:168", "(5)"): "the placeholder static loads when none are given: "
    "four of them are read and every derived value replaces them",
    ("models/loaded_vehicle.py:52", "(moment_y + added * p.cg_y)"): "cg_y is 0 in every "
    "vehicle file's parameters (ModelParameters.from_vehicle never sets it)",
    ("estimators/kf/projection.py:76", "(1)"): "x.shape[1] is 1: ca.DM.eye(1) is CasADi's "
    "scalar 1, so W^-1 A^T is A^T all the same (W = I)",
    ("estimators/kf/projection.py:60", "(1)"): "a row left out (mask 0) meets a zero gain "
    "column (K = W^-1 A^T M S^-1): any residual there gives the same update",
    ("estimators/guards/plausibility.py:105", "(1 + jump)"): "rate_gated is read as a truth "
    "value only (logic_or): -1 and 1 are both true",
    ("estimators/logs/readers/chunks.py:29", "(2)"): "CSV_BLOCK sets the bytes read at a "
    "time, not the values: the chunks of rows are cut from any block",
    ("estimators/logs/readers/chunks.py:53", "(2)"): "the block that reads the header line: "
    "a larger one reads the same names",
}


@dataclass(frozen=True)
class Outcome:
    area: str
    mutant: Mutant
    status: str  # killed, survived, timeout, equivalent
    by: str  # the first failing test, or what stopped the run
    seconds: float


def _copy_checkout(target: Path) -> Path:
    """The tracked and new files of the checkout under ``target/wheelload`` (the package
    root is the checkout's root)."""
    listed = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT, capture_output=True, text=True, check=True,
    ).stdout.split("\n")  # fmt: skip
    package = target / "wheelload"
    for name in filter(None, listed):
        source = ROOT / name
        if source.is_file():
            (package / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, package / name)
    return package


def _pytest(package: Path, tests: tuple[str, ...], scratch: Path, timeout: float | None):
    """Run ``tests`` of the copy in ``package`` with that copy on the path; (rc, output)."""
    env = {**os.environ, "PYTHONPATH": str(package.parent), "TMPDIR": str(scratch),
           "PYTHONDONTWRITEBYTECODE": "1"}  # fmt: skip
    command = [sys.executable, "-m", "pytest", "-x", "-q", "--no-header", "-rfE", "--tb=no",
               "-p", "no:cacheprovider", "-o", "addopts=", *tests]  # fmt: skip
    try:
        run = subprocess.run(command, cwd=package, env=env, capture_output=True, text=True,
                             timeout=timeout)  # fmt: skip
    except subprocess.TimeoutExpired:
        return None, ""
    return run.returncode, run.stdout + run.stderr


def _first_failure(output: str) -> str:
    found = re.search(r"^(?:FAILED|ERROR) (\S+)", output, re.MULTILINE)
    if found:
        return found.group(1)
    lines = [line for line in output.strip().splitlines() if line.strip()]
    return lines[-1][:120] if lines else "no output"


def _run_one(area: str, mutant: Mutant, package: Path, scratch: Path, timeout: float | None,
             tests: tuple[str, ...] | None = None) -> Outcome:  # fmt: skip
    """``mutant`` written into the copy ``package``, the area's ``tests`` run, the copy
    restored."""
    target = package / mutant.path
    original = target.read_text()
    target.write_text(mutant.apply(original))
    began = time.perf_counter()
    try:
        rc, output = _pytest(package, tests or AREAS[area].tests, scratch, timeout)
    finally:
        target.write_text(original)
    seconds = time.perf_counter() - began
    if (mutant.where, mutant.after) in EQUIVALENT and rc == 0:
        return Outcome(area, mutant, "equivalent", EQUIVALENT[mutant.where, mutant.after], seconds)
    if rc is None:
        return Outcome(area, mutant, "timeout", f"over {timeout:.0f} s", seconds)
    if rc == 0:
        return Outcome(area, mutant, "survived", "", seconds)
    return Outcome(area, mutant, "killed", _first_failure(output), seconds)


def draw(areas: list[str], sample: int, seed: int) -> list[tuple[str, Mutant]]:
    """The named mutants of ``areas`` and ``sample`` random ones of each (fixed ``seed``)."""
    chosen = [(area, m) for area, m in named_mutants() if area in areas]
    for area in areas:
        pool = []
        for path in AREAS[area].files():
            pool.extend(mutants((ROOT / path).read_text(), path))
        picked = random.Random(f"{seed}:{area}").sample(pool, min(sample, len(pool)))
        chosen.extend((area, m) for m in sorted(picked, key=lambda m: (m.path, m.line, m.col)))
    return chosen


def score_table(outcomes: list[Outcome]) -> str:
    """The score per area and the table of mutants, as Markdown."""
    lines = ["| area | mutants | killed | survived | equivalent | score |",
             "|---|---|---|---|---|---|"]  # fmt: skip
    for area in dict.fromkeys(o.area for o in outcomes):
        mine = [o for o in outcomes if o.area == area]
        killed = sum(o.status in ("killed", "timeout") for o in mine)
        survived = sum(o.status == "survived" for o in mine)
        equivalent = sum(o.status == "equivalent" for o in mine)
        scored = killed + survived
        lines.append(f"| {area} | {len(mine)} | {killed} | {survived} | {equivalent} | "
                     f"{100.0 * killed / max(scored, 1):.1f} % |")  # fmt: skip
    lines += ["", "| # | area | mutant | file:line | before -> after | status | killed by |",
              "|---|---|---|---|---|---|---|"]  # fmt: skip
    for k, o in enumerate(outcomes, 1):
        lines.append(f"| {k} | {o.area} | {o.mutant.operator} | {o.mutant.where} | "
                     f"{_change(o.mutant)} | "
                     f"{o.status} | {_escaped(o.by)} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def _change(mutant: Mutant) -> str:
    return f"`{_cell(mutant.before)}` -> `{_cell(mutant.after)}`"


def _cell(text: str) -> str:
    text = " ".join(text.split())
    return _escaped(text[:70] + "...") if len(text) > 73 else _escaped(text)


def _escaped(text: str) -> str:
    """``text`` on one line, safe in a Markdown table cell."""
    return " ".join(text.split()).replace("|", "\\|")


def campaign(chosen, workers, timeout_factor, known=None, progress=print) -> list[Outcome]:
    """Run the ``chosen`` (area, mutant) pairs but those whose outcome is ``known`` (by
    index); every outcome in the order chosen."""
    outcomes: dict[int, Outcome] = dict(known or {})
    todo = [(k, area, m) for k, (area, m) in enumerate(chosen) if k not in outcomes]
    areas = list(dict.fromkeys(area for _, area, _ in todo))
    with tempfile.TemporaryDirectory(prefix="wheelload-mutation-") as folder:
        folder = Path(folder)
        scratch = folder / "tmp"  # one build folder for all workers: unchanged C builds once
        scratch.mkdir()
        packages = [_copy_checkout(folder / f"w{k}") for k in range(workers)]
        timeouts = {}
        for area in areas:
            began = time.perf_counter()
            rc, output = _pytest(packages[0], AREAS[area].tests, scratch, 3600.0)
            if rc != 0:
                sys.exit(f"campaign: the unmutated tests of {area} fail: "
                         f"{_first_failure(output)}")  # fmt: skip
            timeouts[area] = max(60.0, timeout_factor * (time.perf_counter() - began))
            progress(f"{area}: tests pass unmutated in {time.perf_counter() - began:.0f} s")
        free = list(packages)
        with concurrent.futures.ThreadPoolExecutor(workers) as pool:
            pending = {}

            def collect(future):
                k, package = pending.pop(future)
                outcomes[k] = future.result()
                free.append(package)
                _report(progress, k, len(chosen), outcomes[k])

            for index, area, mutant in todo:
                if len(pending) == workers:
                    done, _ = concurrent.futures.wait(
                        pending, return_when=concurrent.futures.FIRST_COMPLETED)  # fmt: skip
                    for future in done:
                        collect(future)
                package = free.pop()
                future = pool.submit(_run_one, area, mutant, package, scratch, timeouts[area])
                pending[future] = (index, package)
            for future in concurrent.futures.as_completed(list(pending)):
                collect(future)
    return [outcomes[k] for k in range(len(chosen))]


def read_table(path: Path, chosen) -> dict[int, Outcome]:
    """The outcomes an earlier table holds for the ``chosen`` mutants, by index: the killed
    ones, matched by area, place and change (survivors and equivalents are run again)."""
    killed = {}
    for line in path.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        if len(cells) == 7 and cells[0].isdigit() and cells[5] in ("killed", "timeout"):
            killed[cells[1], cells[3], cells[4]] = (cells[5], cells[6])
    known = {}
    for k, (area, m) in enumerate(chosen):
        found = killed.get((area, m.where, _change(m)))
        if found:
            known[k] = Outcome(area, m, found[0], found[1], 0.0)
    return known


def _report(progress, k, total, outcome):
    m = outcome.mutant
    progress(f"[{k + 1}/{total}] {outcome.status:9s} {m.where} {_cell(m.before)} -> "
             f"{_cell(m.after)} {outcome.by} ({outcome.seconds:.0f} s)")  # fmt: skip


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--area", action="append", choices=sorted(AREAS),
                        help="an area to mutate (repeat; default all)")  # fmt: skip
    parser.add_argument("--sample", type=int, default=60, help="random mutants per area")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--timeout-factor", type=float, default=4.0,
                        help="a mutant's run may take this times the unmutated run")  # fmt: skip
    parser.add_argument("--out", type=Path, help="the table as Markdown (a new file)")
    parser.add_argument("--force", action="store_true", help="overwrite --out")
    parser.add_argument("--only", action="append", default=[], metavar="FILE:LINE",
                        help="run only the drawn mutants at this place (repeat)")  # fmt: skip
    parser.add_argument("--list", action="store_true", help="list the drawn mutants and stop")
    parser.add_argument("--update", type=Path, metavar="TABLE",
                        help="keep the killed mutants TABLE holds, run the rest")  # fmt: skip
    args = parser.parse_args(argv)
    if args.update and args.only:
        parser.error("give --update or --only, not both")
    if args.out and args.out.exists() and not args.force:
        parser.error(f"{args.out} exists: give another --out or --force")
    if args.update and not args.update.is_file():
        parser.error(f"no table {args.update}: give the --out of an earlier run")
    if args.update and args.out and args.out.resolve() == args.update.resolve():
        parser.error(f"{args.out} is the table read by --update: give another --out")
    chosen = [(area, m) for area, m in draw(args.area or list(AREAS), args.sample, args.seed)
              if not args.only or m.where in args.only]  # fmt: skip
    if args.list:
        for area, m in chosen:
            print(f"{area:9s} {m.where} {m.operator:11s} {_cell(m.before)} -> {_cell(m.after)}")
        return 0
    known = read_table(args.update, chosen) if args.update else None
    outcomes = campaign(chosen, args.workers, args.timeout_factor, known,
                        progress=lambda line: print(line, flush=True))  # fmt: skip
    table = score_table(outcomes)
    print(table)
    if args.out:
        partial = args.out.with_name(f".{args.out.name}.partial")
        partial.write_text(table)
        partial.replace(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
