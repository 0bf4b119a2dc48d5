"""Named layouts: the tuning vector, the carried state and the C parameter struct are declared
once (estimators/kernels/layout.py), and nothing indexes them by integer.

The rule is read from the source's syntax tree: a subscript of a name that holds one of these
vectors (``tuning``, ``tuned``, the carried state ``m`` / ``m_next``, ``params``) with an integer
literal anywhere in the index is a positional read the declaration cannot move.
"""

import ast
import re
from pathlib import Path

import numpy as np

from wheelload.estimators.codegen.kf import generate
from wheelload.estimators.codegen.runtime_parameters import PARAMETERS, runtime_fields
from wheelload.estimators.guards.monitor_state import MONITOR
from wheelload.estimators.kf.step import step_function
from wheelload.estimators.kf.tuning import TUNED, TUNING, noise_densities, tuning_vector
from wheelload.models import ModelParameters, example_vehicle_path, load_vehicle

ROOT = Path(__file__).resolve().parent.parent
#: Names that hold a layout's vector, and names that hold a list of such vectors.
LAYOUT_NAMES = {"tuning", "tuned", "m", "m_next", "params"}
LAYOUT_LISTS = {"tunings"}


def _name(node: ast.AST) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    return node.attr if isinstance(node, ast.Attribute) else None


def _has_integer(node: ast.AST) -> bool:
    return any(isinstance(n, ast.Constant) and type(n.value) is int for n in ast.walk(node))


def integer_indexes(source: str) -> list[str]:
    """The subscripts of ``source`` that index a layout's vector by an integer literal."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Subscript) or not _has_integer(node.slice):
            continue
        base = node.value
        held = _name(base) in LAYOUT_NAMES
        listed = isinstance(base, ast.Subscript) and _name(base.value) in LAYOUT_LISTS
        if held or listed:
            found.append(f"{node.lineno}: {ast.unparse(node)}")
    return found


def test_the_rule_finds_integer_indexes():
    source = (
        "q = tuning[0]\nr = self.tuning[2:5]\nx = m_next[0:MONITOR_END]\n"
        "y = tunings[j][0]\nok = TUNING.value(tuning, 'process_noise_density')\n"
        "k = tunings[0]\nz = other[0]\n"
    )
    assert [hit.split(": ")[1] for hit in integer_indexes(source)] == [
        "tuning[0]", "self.tuning[2:5]", "m_next[0:MONITOR_END]", "tunings[j][0]",
    ]  # fmt: skip


def test_no_integer_index_into_a_layout():
    hits = []
    for folder in ("estimators", "studies"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            hits += [f"{path.relative_to(ROOT)}:{hit}" for hit in integer_indexes(path.read_text())]
    assert hits == []


def test_layout_sizes_add_to_the_vectors():
    vehicle = load_vehicle(example_vehicle_path())
    step = step_function()
    assert sum(field.size for field in TUNING.fields) == TUNING.size == len(tuning_vector(vehicle))
    assert TUNING.size == step.nnz_in("tuning")
    assert sum(field.size for field in MONITOR.fields) == MONITOR.size == step.nnz_in("m")
    assert MONITOR.size == step.nnz_out("m_next")
    sizes = len(ModelParameters.names()) + TUNING.size + 1
    assert PARAMETERS.size == sizes == len(runtime_fields())


def test_the_c_struct_follows_the_declaration(tmp_path):
    """The generated struct's members, their defaults' comments and the name table are the
    declaration's names in its order (a reordered declaration reorders the C with them)."""
    library = generate(example_vehicle_path(), tmp_path)
    header = library.header.read_text()
    struct = re.search(r"typedef struct \{([^}]*)\} wheelload_kf_params;", header).group(1)
    members = re.findall(r"wheelload_kf_real (\w+);", struct)
    assert tuple(members) == PARAMETERS.names()
    source = library.source.read_text()
    comments = re.findall(r"^    [-+0-9.eE]+[f]?, /\* (\w+) \*/$", source, re.MULTILINE)
    assert tuple(comments) == PARAMETERS.names()


def test_tune_writes_the_declared_file_keys():
    """The densities ``tune`` fits carry the vehicle file's [filter] key of their declaration,
    and reading the file's values through the keys gives the tuning vector's entries."""
    vehicle = load_vehicle(example_vehicle_path())
    vector = tuning_vector(vehicle)
    for field in TUNED.fields:
        assert field.file_key == ("filter", field.name)
        np.testing.assert_array_equal(
            np.ravel(getattr(vehicle.filter, field.name)),
            np.ravel(TUNING.value(vector, field.name)),
        )


def test_the_tuned_change_set_takes_the_declared_keys():
    """``tune``'s change set: each fitted field under its declared file key, in declaration
    order, a vector field as a list; the values are the fitted ones."""
    from wheelload.studies.pipeline.tuning import density_changes

    vehicle = load_vehicle(example_vehicle_path())
    fitted = noise_densities(vehicle) * 2.0
    changes = density_changes(fitted, "a note")
    assert list(changes) == [field.file_key for field in TUNED.fields]
    assert changes["filter", "process_noise_density"] == (fitted[0], "tuned: a note")
    assert changes["filter", "constraint_noise_density"][0] == list(fitted[2:5])
    assert changes["filter", "constraint_noise_acceleration_density"][0] == list(fitted[7:10])
