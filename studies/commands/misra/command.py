"""``wheelload misra``: MISRA C:2012 findings on generated C, per file and rule.

Runs cppcheck's MISRA add-on (:mod:`wheelload.estimators.codegen.misra`) on a folder written by
``wheelload codegen`` (KF library, tyre step, embedded MHE) or on a source FMU, and prints per
file the findings per rule, required or advisory, deviated or open (the folder's
``MISRA_DEVIATIONS.md``), with cppcheck's seconds per file. ``--save FILE`` keeps the findings
(JSON); ``--baseline FILE`` shows a saved run beside this one (before -> after). Exit status 1
when a required finding is open (neither fixed nor in the deviation record).
"""

from __future__ import annotations

import argparse
import collections
import json
import tempfile
import zipfile
from pathlib import Path

from wheelload.estimators.codegen.misra import Report, analyse, category, cppcheck
from wheelload.estimators.logs.output_files import check_outputs, write_text
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(writes=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("misra", help=CATALOG["misra"].summary)
    parser.add_argument(
        "target", metavar="FOLDER|FMU", help="a folder written by wheelload codegen, or its .fmu"
    )
    parser.add_argument("--save", metavar="FILE", help="also write the findings (JSON)")
    parser.add_argument(
        "--baseline", metavar="FILE", help="a run saved with --save: print before -> after"
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    target = Path(args.target)
    if not target.exists():
        raise ValueError(f"{target}: no such folder or FMU")
    if cppcheck() is None:
        raise ValueError("cppcheck not found: install it (apt-get install cppcheck) and retry")
    save = Path(args.save) if args.save else None
    if save is not None:
        check_outputs([save], [target], force=args.force)
    baseline = _baseline(Path(args.baseline)) if args.baseline else None
    report = _analyse(target)
    for line in table(report, baseline):
        print(line)
    if save is not None:
        write_text(save, json.dumps(report.to_dict(), indent=1) + "\n", replace=args.force)
    return 1 if report.required_open() else 0


def _analyse(target: Path) -> Report:
    """A folder as it is; an FMU's ``sources`` (FMPy's FMI headers on the include path)."""
    if target.is_dir():
        return analyse(target)
    with tempfile.TemporaryDirectory(prefix="wheelload-fmu-") as scratch:
        with zipfile.ZipFile(target) as archive:
            names = [n for n in archive.namelist() if n.startswith("sources/")]
            archive.extractall(scratch, names)
        return analyse(Path(scratch) / "sources", includes=fmi_headers())


def fmi_headers() -> list[Path]:
    """FMPy's FMI 3.0 headers (an FMU wrapper includes ``fmi3Functions.h``), if installed."""
    try:
        import fmpy
    except ImportError:
        return []
    return [Path(fmpy.__file__).parent / "c-code"]


def _baseline(path: Path) -> collections.Counter:
    try:
        saved = json.loads(path.read_text("utf-8"))
        return collections.Counter((file, rule) for file, _, rule in saved["findings"])
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ValueError(f"{path}: not a run saved with wheelload misra --save ({error})") from None


def table(report: Report, baseline: collections.Counter | None) -> list[str]:
    """Per file: one line per rule (category, findings [before -> after], deviated), a total."""
    now = collections.Counter((f.file, f.rule) for f in report.findings)
    deviated = {(f.file, f.rule) for f in report.findings if report.deviated(f)}
    files = sorted({file for file, _ in now} | {file for file, _ in baseline or {}}
                   | set(report.seconds))  # fmt: skip
    lines = [f"{'file / rule':<34} {'category':<9} {'findings':>12}  deviation"]
    for file in files:
        seconds = report.seconds.get(file)
        lines.append(file + (f"  (cppcheck {seconds:.1f} s cpu)" if seconds is not None else ""))
        rules = {r for f, r in now if f == file} | {r for f, r in baseline or {} if f == file}
        rules = sorted(rules, key=_rule_key)
        for rule in rules:
            count = _count(baseline, now, (file, rule))
            mark = "deviated" if (file, rule) in deviated else ("OPEN" if (
                category(rule) == "required" and now[file, rule]) else "")  # fmt: skip
            lines.append(f"  {rule:<32} {category(rule):<9} {count:>12}  {mark}")
        for kind in ("required", "advisory"):
            after = sum(n for (f, r), n in now.items() if f == file and category(r) == kind)
            before = (
                None
                if baseline is None
                else sum(n for (f, r), n in baseline.items() if f == file and category(r) == kind)
            )
            text = str(after) if before is None else f"{before} -> {after}"
            lines.append(f"  {'all ' + kind:<32} {kind:<9} {text:>12}")
    open_findings = report.required_open()
    lines.append(f"{len(open_findings)} open required findings" + (
        ": " + ", ".join(f"{f.file}:{f.line} rule {f.rule}" for f in open_findings[:10])
        if open_findings else ""))  # fmt: skip
    return lines


def _count(baseline: collections.Counter | None, now: collections.Counter, key) -> str:
    return str(now[key]) if baseline is None else f"{baseline[key]} -> {now[key]}"


def _rule_key(rule: str) -> tuple[int, ...]:
    return tuple(int(part) for part in rule.split("."))
