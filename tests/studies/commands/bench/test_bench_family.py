"""``wheelload bench family`` runs on a short log and prints one parsable line per method."""

import math
import re

from wheelload.estimators.registry import method, methods
from wheelload.studies.cli import main
from wheelload.studies.pipeline.example_log import example_log_path

NUMBER = r"([0-9.]+)"
TRIPLE = rf"{NUMBER} / {NUMBER} / {NUMBER}"


def test_bench_family_prints_a_line_per_method_and_model(tmp_path, capsys):
    lines = example_log_path().read_text().splitlines()
    log = tmp_path / "short.csv"
    log.write_text("\n".join(lines[:301]) + "\n")  # header + 300 samples (3 s)
    code = main(["bench", "family", "--log", str(log), "--repeats", "2", "--suspension", "both"])
    assert code == 0
    out = capsys.readouterr().out
    assert "short.csv, 300 samples" in out
    starts = re.findall(rf"load average at start: {NUMBER} {NUMBER} {NUMBER}", out)
    ends = re.findall(rf"load average at end: +{NUMBER} {NUMBER} {NUMBER}", out)
    assert len(starts) == 1 and len(ends) == 1
    rows = {}
    for name, model, *values in re.findall(rf"^(\S+) +(-|full|paper) +{TRIPLE}  {TRIPLE}$", out,
                                           re.MULTILINE):  # fmt: skip
        rows[(name, model)] = [float(v) for v in values]
    expected = set()
    for name in methods():
        models = ("full", "paper") if method(name).model_choice else ("-",)
        expected |= {(name, model) for model in models}
    assert set(rows) == expected
    for key, (low, mid, high, r_low, r_mid, r_high) in rows.items():
        assert all(math.isfinite(v) and v > 0 for v in (low, mid, high, r_low, r_mid, r_high)), key
        assert low <= mid <= high and r_low <= r_mid <= r_high, key
    assert rows[("kf", "-")][3:] == [1.0, 1.0, 1.0]


def test_bench_family_methods_option_adds_the_kf(tmp_path, capsys):
    lines = example_log_path().read_text().splitlines()
    log = tmp_path / "short.csv"
    log.write_text("\n".join(lines[:101]) + "\n")
    assert main(["bench", "family", "--log", str(log), "--repeats", "1", "--methods", "D",
                 "--suspension", "paper"]) == 0  # fmt: skip
    table = [line.split()[:2] for line in capsys.readouterr().out.splitlines()[3:-1]]
    assert table == [["kf", "-"], ["D", "paper"]]
    assert main(["bench", "family", "--methods", "nosuch"]) == 2
    assert "unknown method 'nosuch'" in capsys.readouterr().err
