"""MISRA C:2012: the generated KF library and its tyre step carry no required finding that the
deviation record written beside them does not list (cppcheck's MISRA add-on, real files).

The library's straight-line kernels are analysed once per statement shape
(:func:`~wheelload.estimators.codegen.misra.shape_view`; test_misra.py checks that this finds
what the whole text gives). Skipped, with the reason, where cppcheck is not installed.
"""

from __future__ import annotations

import pytest

from wheelload.estimators.codegen.deviations import RECORD_NAME
from wheelload.estimators.codegen.kf import CodegenOptions, generate
from wheelload.estimators.codegen.misra import analyse, cppcheck
from wheelload.models import example_vehicle_path

pytestmark = [
    pytest.mark.heavy(50),  # seconds (tests/conftest.py)
    pytest.mark.skipif(
        cppcheck() is None, reason="cppcheck not installed (apt-get install cppcheck)"
    ),
]


def test_generated_kf_library_has_no_open_required_finding(tmp_path):
    generate(example_vehicle_path(), tmp_path, CodegenOptions(tyre_forces=True))
    assert (tmp_path / RECORD_NAME).is_file()
    sources = [tmp_path / "wheelload_kf.c", tmp_path / "wheelload_kf_tyre.c"]
    report = analyse(tmp_path, sources)
    assert report.required_open() == []
    # The record's library deviation is in use (restrict in the batched step), no other.
    assert {f.rule for f in report.findings if report.deviated(f)} == {"8.14"}
