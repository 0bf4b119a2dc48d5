"""The mutation campaign's own parts: each operator's mutant, what is never mutated, and one
real run (a copy of the checkout, the real pytest) that kills a mutant and lets a no-op live."""

import ast
from pathlib import Path

import pytest
from campaign import (
    AREAS,
    ROOT,
    Outcome,
    _copy_checkout,
    _run_one,
    draw,
    named_mutants,
    read_table,
    score_table,
)
from mutants import Mutant, mutants

SOURCE = '''"""Docstring 1 + 2."""
import casadi as ca


def f(a: int = 3, b=4):
    """Docstring a < b."""
    if a < b and b >= 0:
        raise ValueError(f"a {a + 1} too small")
    log.info("at %d", a - 1)
    return ca.if_else(a > 0, ca.fmax(a, b) * -b, g(a, b)) ** 2
'''


def found(source=SOURCE):
    return {(m.operator, m.before, m.after) for m in mutants(source, "m.py")}


def test_each_operator_makes_its_mistake():
    expected = {
        ("compare", "a < b", "(a <= b)"),
        ("compare", "b >= 0", "(b > 0)"),
        ("compare", "a > 0", "(a >= 0)"),
        ("boolean", "a < b and b >= 0", "(a < b or b >= 0)"),
        ("number", "0", "(1)"),
        ("number", "4", "(5)"),
        ("number", "2", "(3)"),
        ("sign", "-b", "(b)"),
        ("counterpart", "ca.fmax(a, b)", "(ca.fmin(a, b))"),
        ("arguments", "g(a, b)", "(g(b, a))"),
        ("binary", "ca.fmax(a, b) * -b", "(ca.fmax(a, b) / -b)"),
    }
    assert expected <= found()
    assert ("branches", "ca.if_else(a > 0, ca.fmax(a, b) * -b, g(a, b))",
            "(ca.if_else(a > 0, g(a, b), ca.fmax(a, b) * -b))") in found()  # fmt: skip


def test_messages_docstrings_annotations_and_commuting_arguments_are_left_alone():
    befores = {before for _, before, _ in found()}
    assert not {"1 + 2", "a + 1", "a - 1", "1", "a < b)"} & befores
    assert ("arguments", "ca.fmax(a, b)", "(ca.fmax(b, a))") not in found()
    assert not any("int" in before for before in befores)


def test_every_mutant_of_a_model_module_compiles_and_changes_one_place():
    path = "models/suspension/elements.py"
    source = (ROOT / path).read_text()
    original = ast.dump(ast.parse(source))
    for mutant in mutants(source, path):
        changed = mutant.apply(source)
        assert ast.dump(ast.parse(changed)) != original, mutant
        lines, new_lines = source.splitlines(), changed.splitlines()
        assert lines[: mutant.line - 1] == new_lines[: mutant.line - 1], mutant


def test_a_line_with_non_ascii_text_is_mutated_at_the_right_column():
    source = 'UNITS = {"°": (1, 3.0 / 180.0)}\n'
    (mutant,) = [m for m in mutants(source, "u.py") if m.operator == "binary"]
    assert mutant.apply(source) == 'UNITS = {"°": (1, (3.0 * 180.0))}\n'


def test_named_mutants_are_found_in_the_sources():
    for area, mutant in named_mutants():
        assert area in AREAS
        source = (ROOT / mutant.path).read_text()
        assert mutant.before in source and mutant.apply(source) != source


def test_score_counts_equivalent_mutants_apart():
    m = Mutant("a.py", 1, 0, 1, 1, "number", "1", "(2)")
    statuses = ("killed", "killed", "timeout", "survived", "equivalent")
    outcomes = [Outcome("models", m, status, "t", 1.0) for status in statuses]
    table = score_table(outcomes)
    assert "| models | 5 | 3 | 1 | 1 | 75.0 % |" in table


@pytest.fixture(scope="module")
def checkout_copy(tmp_path_factory) -> Path:
    return _copy_checkout(tmp_path_factory.mktemp("mutation"))


def test_a_real_run_kills_a_wrong_unit_and_lets_a_no_op_live(checkout_copy, tmp_path):
    (wrong_mph,) = [m for area, m in named_mutants() if "mph" in m.before]
    area = "readers"
    outcome = _run_one(area, wrong_mph, checkout_copy, tmp_path, timeout=None,
                       tests=("tests/estimators/logs/test_units.py",))  # fmt: skip
    assert outcome.status == "killed"
    assert (
        outcome.by
        == "tests/estimators/logs/test_units.py::test_unit_factor_equals_its_definition[mph]"
    )
    no_op = Mutant(wrong_mph.path, wrong_mph.line, wrong_mph.col, wrong_mph.end_line,
                   wrong_mph.end_col, "none", wrong_mph.before, wrong_mph.before)  # fmt: skip
    outcome = _run_one(area, no_op, checkout_copy, tmp_path, timeout=None,
                       tests=("tests/estimators/logs/test_units.py",))  # fmt: skip
    assert outcome.status == "survived"
    source = (checkout_copy / wrong_mph.path).read_text()
    assert source == (ROOT / wrong_mph.path).read_text()  # the copy restored


def test_an_earlier_table_keeps_its_killed_mutants_of_the_same_place_and_change(tmp_path):
    chosen = draw(["readers"], 3, seed=0)
    statuses = ["killed", "survived", "timeout", "equivalent"]
    outcomes = [Outcome(area, m, statuses[k % 4], f"t{k}", 1.0)
                for k, (area, m) in enumerate(chosen)]  # fmt: skip
    table = tmp_path / "table.md"
    table.write_text(score_table(outcomes))
    known = read_table(table, chosen)
    assert sorted(known) == [k for k, o in enumerate(outcomes) if o.status in statuses[::2]]
    assert all(known[k].mutant == chosen[k][1] and known[k].by == f"t{k}" for k in known)
    # Another draw, shifted by one: the same mutants are found at their new places.
    shifted = [chosen[-1], *chosen[:-1]]
    assert {k - 1 for k in read_table(table, shifted)} == set(known)
