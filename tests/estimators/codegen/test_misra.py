"""MISRA C:2012 report of the generated C (cppcheck's MISRA add-on, real files, real cppcheck).

The FMU wrapper carries no required finding that its shipped deviation record does not list
(the KF library's: test_misra_library.py); a planted required finding is caught; the
statement-shape view gives the findings of the whole text on emitted straight-line code.
Skipped, with the reason, where cppcheck is not installed (.ci/run installs it).
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import casadi as ca
import pytest

from wheelload.estimators.codegen.deviations import (
    KF_DEVIATIONS,
    RECORD_NAME,
    read_deviations,
    write_deviation_record,
)
from wheelload.estimators.codegen.fmu import generate_fmu
from wheelload.estimators.codegen.misra import analyse, cppcheck, shape, shape_view
from wheelload.estimators.kernels.c_emitter import Precision, emit_statements
from wheelload.models import example_vehicle_path

pytestmark = pytest.mark.heavy(15)  # seconds (tests/conftest.py)

needs_cppcheck = pytest.mark.skipif(
    cppcheck() is None, reason="cppcheck not installed (apt-get install cppcheck)"
)


def test_shape_ignores_name_digits_indices_and_numbers_but_zero_and_one():
    assert shape("    w12 = w3 * x[4];") == shape("w7 = w100 * x[0];")
    assert shape("w1 = w2 + 2.5;") == shape("w1 = w2 + 1e-3;")
    assert shape("w1 = w2 + 0.0;") != shape("w1 = w2 + 0;")  # rule 2.2 looks for a literal 0
    assert shape("w1 = w2 * 1;") != shape("w1 = w2 * 3;")
    assert shape("w1 = 2.0f;") != shape("w1 = 2.0;")  # essential type: the suffix stays


def test_shape_view_keeps_line_numbers_and_stands_for_every_statement():
    body = [f"    w{k} = w{k - 1} * x[{k % 4}];" for k in range(1, 60)]
    body += [f"    w{k} = sqrt(w{k - 1});" for k in range(60, 100)]
    text = "void f(void)\n{\n" + "\n".join(body) + "\n}\n"
    view, stands_for = shape_view(text)
    lines = view.splitlines()
    assert len(lines) == len(text.splitlines())
    assert [k for k, line in enumerate(lines, 1) if line.strip().startswith("w")] == [3, 62]
    assert sorted(sum(stands_for.values(), [])) == list(range(3, 102))


def test_deviation_record_reads_back_as_written(tmp_path):
    write_deviation_record(tmp_path, KF_DEVIATIONS, "my_kf")
    assert read_deviations(tmp_path) == tuple(d.for_prefix("my_kf") for d in KF_DEVIATIONS)


def _emitted_function(tmp_path: Path) -> Path:
    """A C file whose function body is emitted straight-line code of every operation the
    step uses (selects, min/max, sqrt, comparisons, literals 0, 1 and others)."""
    x = ca.SX.sym("x", 6)
    terms = []
    for k in range(6):
        a, b = x[k], x[(k + 1) % 6]
        terms += [a * b + 2.5, ca.sqrt(ca.fabs(a)), ca.fmin(a, b), ca.fmax(a, 0.5),
                  ca.if_else(a < b, a, b), (a <= 1.0) * b, a / (b + 1.0) - 0.0, -a]  # fmt: skip
    f = ca.Function("f", [x], [ca.vertcat(*terms)])
    body = emit_statements(f, ["x[{}]"], ["y[{}]"], Precision.DOUBLE, "double")
    source = tmp_path / "emitted.c"
    source.write_text(
        '#include <math.h>\n#include "emitted.h"\n'
        "void emitted(const double x[6], double y[48])\n{\n"
        + "\n".join(f"    {line}" for line in body.splitlines())
        + "\n}\n"
    )
    (tmp_path / "emitted.h").write_text(
        "#ifndef EMITTED_H\n#define EMITTED_H\nvoid emitted(const double x[6], double y[48]);\n"
        "#endif\n"
    )
    return source


@needs_cppcheck
def test_shape_view_finds_what_the_whole_text_gives(tmp_path):
    # Tolerance: none; the same finding set (file, line, rule) on emitted code.
    source = _emitted_function(tmp_path)
    assert len(shape_view(source.read_text())[1]) < len(source.read_text().splitlines()) / 3
    whole = analyse(tmp_path, shapes=False)
    viewed = analyse(tmp_path)
    assert whole.findings  # the emitted code has findings to compare (advisory 12.1, 10.x)
    assert viewed.findings == whole.findings


@needs_cppcheck
def test_a_required_finding_outside_the_record_is_open(tmp_path):
    # Rule 10.3 (required): a double assigned to an int.
    (tmp_path / "planted.c").write_text(
        "int planted(double d);\nint planted(double d)\n{\n    const int i = d;\n    return i;\n}\n"
    )
    write_deviation_record(tmp_path, KF_DEVIATIONS, "wheelload_kf")
    report = analyse(tmp_path)
    assert [(f.file, f.line, f.rule) for f in report.required_open()] == [("planted.c", 4, "10.3")]


@needs_cppcheck
def test_fmu_wrapper_has_no_open_required_finding(tmp_path):
    fmu = generate_fmu(example_vehicle_path(), tmp_path / "fmu")
    with zipfile.ZipFile(fmu.path) as archive:
        names = [n for n in archive.namelist() if n.startswith("sources/")]
        archive.extractall(tmp_path / "x", names)
    sources = tmp_path / "x" / "sources"
    assert (sources / RECORD_NAME).is_file()
    pytest.importorskip("fmpy", reason="the FMU wrapper needs FMPy's FMI 3.0 headers")
    import fmpy

    headers = Path(fmpy.__file__).parent / "c-code"
    report = analyse(sources, [sources / "wheelload_kf_fmu.c"], includes=[headers])
    assert report.required_open() == []
