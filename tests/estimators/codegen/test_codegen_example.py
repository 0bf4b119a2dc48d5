"""The generated example program reads CSV logs strictly: real gcc build, small logs in tmp_path.

Rows in the example's messages count data rows from 1 (wheelload's Python
reader counts from 0) and also give the line of the file.
"""

import numpy as np
import pytest
from c_parity import kf_program, run_program

from wheelload.estimators import read_log
from wheelload.estimators.codegen.kf import CodegenOptions
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.models import example_vehicle_path

COLUMNS = [
    "t",
    "vx",
    "ax",
    "ay",
    "az",
    *(f"{s}_{w}" for s in "dv" for w in ("fl", "fr", "rl", "rr")),
]
N_ROWS = 30
BAD_ROW = 9  # 0-based data row that the cases below edit: row 10, line 11 of the file


def example_binary(tmp_path_factory, precision):
    out = tmp_path_factory.mktemp(f"example_{precision.value}")
    return kf_program(example_vehicle_path(), out, CodegenOptions(precision=precision))


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    return example_binary(tmp_path_factory, Precision.DOUBLE)


def header():
    return ",".join(COLUMNS)


def rows():
    """N_ROWS rows of a gentle slalom at 100 Hz, as lists of field texts."""
    result = []
    for k in range(N_ROWS):
        t = 0.01 * (k + 1)
        ay = 3.0 * np.sin(2.0 * np.pi * 0.8 * t)
        d = [
            0.002 * np.sin(9.0 * t + w) - 0.0004 * ay * (1 if w % 2 == 0 else -1) for w in range(4)
        ]
        v = [0.018 * np.cos(9.0 * t + w) for w in range(4)]
        values = [t, 20.0, 0.3, ay, 9.81 + 0.05 * np.sin(20.0 * t), *d, *v]
        result.append([f"{value:.10g}" for value in values])
    return result


def text(lines):
    return "".join(f"{line}\n" for line in lines)


def clean_lines():
    return [header(), *(",".join(row) for row in rows())]


def run(binary, log, text_):
    """Run the example on a log with the given text; the estimates file is next to it."""
    log.write_bytes(text_.encode())
    out = log.with_suffix(".out.csv")
    result = run_program(binary, log, out, check=False)
    return result, out


@pytest.fixture(scope="module")
def clean_estimates(example, tmp_path_factory):
    result, out = run(example, tmp_path_factory.mktemp("clean") / "clean.csv", text(clean_lines()))
    assert result.returncode == 0, result.stderr
    estimates = out.read_text()
    assert len(estimates.splitlines()) == N_ROWS + 1
    return estimates


def with_field(column, value, row=BAD_ROW):
    table = rows()
    table[row][COLUMNS.index(column)] = value
    return [header(), *(",".join(fields) for fields in table)]


@pytest.mark.parametrize("blank", ["", "   \t", "\r", "# logger paused"])
def test_blank_line_in_the_middle_is_skipped(example, clean_estimates, tmp_path, blank):
    lines = clean_lines()
    lines.insert(N_ROWS // 2, blank)
    result, out = run(example, tmp_path / "blank.csv", text(lines))
    assert result.returncode == 0, result.stderr
    assert out.read_text() == clean_estimates
    if blank in ("", "# logger paused"):  # the Python reader skips these too
        assert len(read_log(tmp_path / "blank.csv")) == N_ROWS


@pytest.mark.parametrize(
    "bad",
    [
        "-0.00128173828abc",
        "0x9.8p0",
        "inf",
        "-Infinity",
        "nan(1)",
        "1.2.3",
        "1e",
        "--1",
        "1 2",
        ".",
        "e5",
    ],  # fmt: skip
)
def test_malformed_number_is_an_error_naming_row_column_and_text(example, tmp_path, bad):
    result, out = run(example, tmp_path / "bad.csv", text(with_field("d_fl", bad)))
    assert result.returncode == 2
    assert f"column 'd_fl' is not a decimal number at row {BAD_ROW + 1} (line {BAD_ROW + 2})" in (
        result.stderr
    )
    assert f"'{bad}'" in result.stderr
    assert not out.exists()  # no partial estimates left behind


@pytest.mark.parametrize("missing", ["", "nan", "NaN", " NAN "])
def test_empty_or_nan_field_is_a_missing_sample(example, clean_estimates, tmp_path, missing):
    result, out = run(example, tmp_path / "missing.csv", text(with_field("az", missing)))
    assert result.returncode == 0, result.stderr
    estimates = [line.split(",") for line in out.read_text().splitlines()]
    clean = [line.split(",") for line in clean_estimates.splitlines()]
    assert estimates[:BAD_ROW + 1] == clean[:BAD_ROW + 1]  # fmt: skip
    assert estimates[BAD_ROW + 1][-1] != "0"  # the vertical update was skipped
    assert len(estimates) == N_ROWS + 1


@pytest.mark.parametrize(
    ("t", "message"),
    [
        ("", "has no valid time stamp"),
        ("nan", "has no valid time stamp"),
        (f"{0.01 * BAD_ROW:.10g}", "is not increasing"),  # repeats the previous time stamp
        ("0.05", "is not increasing"),
    ],
)
def test_bad_time_stamp_is_an_error_naming_the_row(example, tmp_path, t, message):
    result, out = run(example, tmp_path / "t.csv", text(with_field("t", t)))
    assert result.returncode == 2
    assert f"column 't' {message} at row {BAD_ROW + 1} (line {BAD_ROW + 2})" in result.stderr
    assert not out.exists()


def test_bad_first_time_stamp_is_an_error(example, tmp_path):
    result, _ = run(example, tmp_path / "t0.csv", text(with_field("t", "", row=0)))
    assert result.returncode == 2
    assert "column 't' has no valid time stamp at row 1 (line 2)" in result.stderr


@pytest.mark.parametrize("quoted", [False, True])
def test_header_names_are_trimmed(example, clean_estimates, tmp_path, quoted):
    lines = clean_lines()
    lines[0] = ",".join(f'\t"{name}" ' if quoted else f"  {name} " for name in COLUMNS)
    result, out = run(example, tmp_path / "spaces.csv", text(lines))
    assert result.returncode == 0, result.stderr
    assert out.read_text() == clean_estimates
    if not quoted:  # the Python reader strips names too
        assert len(read_log(tmp_path / "spaces.csv")) == N_ROWS


def test_crlf_line_endings_and_extra_columns_are_read(example, clean_estimates, tmp_path):
    lines = [f"{line},0\r" for line in clean_lines()]
    lines[0] = lines[0].replace(",0\r", ",fz_fl\r")
    result, out = run(example, tmp_path / "crlf.csv", text(lines))
    assert result.returncode == 0, result.stderr
    assert out.read_text() == clean_estimates


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda lines: lines[BAD_ROW + 1].rsplit(",", 1)[0],
            "row 10 (line 11) has 12 fields, the header has 13",
        ),  # fmt: skip
        (
            lambda lines: lines[BAD_ROW + 1] + ",1",
            "row 10 (line 11) has 14 fields, the header has 13",
        ),  # fmt: skip
    ],
)
def test_row_with_the_wrong_number_of_fields_is_an_error(example, tmp_path, edit, message):
    lines = clean_lines()
    lines[BAD_ROW + 1] = edit(lines)
    result, _ = run(example, tmp_path / "fields.csv", text(lines))
    assert result.returncode == 2
    assert message in result.stderr


@pytest.mark.parametrize(
    ("lines", "message"),
    [
        ([], "no header row"),
        (clean_lines()[:2], "needs at least 2 data rows, has 1"),
        ([clean_lines()[0].replace(",ax,", ",t,"), *clean_lines()[1:]], "column 't' appears twice"),
    ],
)
def test_unusable_log_is_an_error(example, tmp_path, lines, message):
    result, _ = run(example, tmp_path / "unusable.csv", text(lines))
    assert result.returncode == 2
    assert message in result.stderr


def test_float_build_rejects_a_value_beyond_float_range(tmp_path_factory, tmp_path):
    binary = example_binary(tmp_path_factory, Precision.FLOAT)
    result, _ = run(binary, tmp_path / "big.csv", text(with_field("az", "1e39")))
    assert result.returncode == 2
    assert "column 'az' is out of range for float at row 10 (line 11): '1e39'" in result.stderr
    result, _ = run(binary, tmp_path / "clean.csv", text(clean_lines()))
    assert result.returncode == 0, result.stderr
