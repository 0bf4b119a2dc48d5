"""The layout's rules, read from the source's own imports (every import, lazy ones too).

- no import circle among the package's modules;
- interface modules (the Estimator protocol, the result type) import no implementation;
- studies and the command line reach estimators through the registry and the package face only
  (benchmarks, which time an implementation itself, excepted: :data:`BENCHMARKS`);
- no estimator imports the ground-truth plant (``wheelload.models.plant``), lazily neither;
- no module imports another module's private name;
- a folder holds few modules (one job a room), a command module is a thin front end;
- tests import no command module (the command line's logic lives in the pipeline).
"""

import ast
from collections import defaultdict
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("models", "estimators", "studies")
#: Modules that define the estimators' interface: nothing of an implementation below them.
INTERFACE = (
    "wheelload.estimators.protocol",
    "wheelload.estimators.result",
    "wheelload.estimators.types",
)
#: Rooms of the estimators that hold implementations (reached through the registry).
IMPLEMENTATION = tuple(
    f"wheelload.estimators.{room}" for room in ("kf", "mhe", "family", "guards", "loops", "kernels")
)
#: Numerical helpers (a median, a first-order filter) the plain types may use.
NUMERICAL_KERNELS = ("wheelload.estimators.kernels",)
#: Benchmarks time implementations against each other, so they may import them directly.
BENCHMARKS = ("wheelload.studies.bench", "wheelload.studies.commands.bench")
#: The declared layers, lowest first: a module imports only from its own layer or below.
#: A module belongs to the layer of the longest prefix that names it.
LAYERS = (
    ("runtime", ("wheelload.models.runtime",)),
    ("models", ("wheelload.models",)),
    ("kernels", ("wheelload.estimators.kernels",)),
    (
        "types",
        (
            "wheelload.estimators.types",
            "wheelload.estimators.result",
            "wheelload.estimators.estimate_figure",
            "wheelload.estimators.protocol",
            "wheelload.estimators.suspension_choice",
        ),
    ),
    ("loops, logs", ("wheelload.estimators.loops", "wheelload.estimators.logs")),
    ("guards", ("wheelload.estimators.guards",)),
    ("kf", ("wheelload.estimators.kf",)),
    (
        "mhe, family, identification",
        (
            "wheelload.estimators.mhe",
            "wheelload.estimators.family",
            "wheelload.estimators.identification",
        ),
    ),
    ("codegen", ("wheelload.estimators.codegen",)),
    ("the door", ("wheelload.estimators",)),
    ("studies", ("wheelload.studies",)),
)
#: Benchmarks time an implementation itself (a compiled loop, a QP window, bare OSQP): the one
#: part of the studies that may import implementations directly.
BENCHMARKS = ("wheelload.studies.bench", "wheelload.studies.commands.bench")
#: The ground-truth plant, which no estimator may be built from.
PLANT = "wheelload.models.plant"
#: Most modules (``__init__`` not counted) one package folder holds.
MOST_MODULES = 16
#: Most lines of a command module (parse the arguments, call the pipeline, print).
MOST_COMMAND_LINES = 250


def module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(("wheelload", *parts))


@cache
def modules() -> dict[str, Path]:
    """Every module of the package by dotted name."""
    found = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            if "__pycache__" not in path.parts:
                found[module_name(path, ROOT)] = path
    return found


def resolve(name: str, known) -> str | None:
    """The module ``name`` is, or is inside (an imported attribute of a module)."""
    while name and name not in known:
        name = name.rpartition(".")[0]
    return name or None


@cache
def imports() -> dict[str, set[tuple[str, str | None]]]:
    """module -> {(imported module, imported name or None)} over every import statement."""
    known = modules()
    table = defaultdict(set)
    for module, path in known.items():
        tree = ast.parse(path.read_text(), str(path))
        bound = {}  # a name this module binds to an imported module
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if target := resolve(alias.name, known):
                        table[module].add((target, None))
                        if alias.asname and target == alias.name:
                            bound[alias.asname] = target
            elif isinstance(node, ast.ImportFrom) and node.module:
                for alias in node.names:
                    full = f"{node.module}.{alias.name}"
                    if full in known:
                        table[module].add((full, None))
                        bound[alias.asname or alias.name] = full
                    elif target := resolve(node.module, known):
                        table[module].add((target, alias.name))
        for node in ast.walk(tree):  # module.name read through a bound module
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
                if node.value.id in bound:
                    table[module].add((bound[node.value.id], node.attr))
    return table


def arrows() -> dict[str, set[str]]:
    """module -> the modules it imports (its own package's ``__init__`` left out)."""
    graph = {module: set() for module in modules()}
    for module, targets in imports().items():
        for target, _ in targets:
            if target != module and not module.startswith(target + "."):
                graph[module].add(target)
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def inside(module: str, rooms) -> bool:
    return any(module == room or module.startswith(room + ".") for room in rooms)


def test_the_circle_finder_finds_a_circle():
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set()}) == []


def test_no_import_circle():
    found = circles(arrows())
    assert not found, "import circles: " + "; ".join(" <-> ".join(c) for c in found)


@pytest.mark.parametrize("interface", INTERFACE)
def test_interface_modules_import_no_implementation(interface):
    offending = sorted(
        {
            target
            for target, _ in imports()[interface]
            if (inside(target, IMPLEMENTATION) and not inside(target, NUMERICAL_KERNELS))
            or target.startswith("wheelload.estimators.codegen")
        }
    )
    assert not offending, f"{interface} imports {offending}"


def test_studies_reach_estimators_through_the_registry():
    """Studies reach implementations through the registry and the face; benchmarks, by rule
    (:data:`BENCHMARKS`), may import the implementation they time."""
    offending = sorted(
        {
            f"{module} -> {target}"
            for module, targets in imports().items()
            if module.startswith("wheelload.studies") and not inside(module, BENCHMARKS)
            for target, _ in targets
            if inside(target, IMPLEMENTATION)
        }
    )
    assert not offending, "\n".join(offending)


def test_the_benchmark_rule_names_existing_folders():
    assert all((ROOT / Path(*room.split(".")[1:])).is_dir() for room in BENCHMARKS)


def plant_references(module: str) -> set[str]:
    """The plant modules ``module`` imports, or names in a string (a lazy import by name)."""
    found = {target for target, _ in imports()[module] if inside(target, (PLANT,))}
    for node in ast.walk(ast.parse(modules()[module].read_text())):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            if node.value == PLANT or node.value.startswith(PLANT + "."):
                found.add(node.value)
    return found


def test_no_estimator_imports_the_plant():
    """The plant is the studies' independent truth: estimators (and the C they emit) are
    built from ``models/`` outside ``models/plant`` and the vehicle description."""
    offending = sorted(
        f"{module} -> {target}"
        for module in modules()
        if module.startswith("wheelload.estimators")
        for target in plant_references(module)
    )
    assert not offending, "\n".join(offending)


def test_the_plant_rule_sees_an_import():
    assert plant_references("wheelload.studies.drive.simulation")


def test_no_private_name_crosses_a_module():
    offending = sorted(
        f"{module} imports {target}.{name}"
        for module, targets in imports().items()
        for target, name in targets
        if name and name.startswith("_") and not name.startswith("__") and target != module
    )
    assert not offending, "\n".join(offending)


def test_every_folder_holds_few_modules():
    counts = defaultdict(int)
    for path in modules().values():
        if path.name != "__init__.py":
            counts[str(path.parent.relative_to(ROOT))] += 1
    crowded = {folder: n for folder, n in counts.items() if n > MOST_MODULES}
    assert not crowded, f"folders with more than {MOST_MODULES} modules: {crowded}"


def test_command_modules_are_thin():
    long = {
        path.name: n
        for path in (ROOT / "studies" / "commands").glob("*.py")
        if (n := len(path.read_text().splitlines())) >= MOST_COMMAND_LINES
    }
    assert not long, f"command modules of {MOST_COMMAND_LINES} lines or more: {long}"


def test_tests_import_no_command_module():
    offending = []
    for path in sorted((ROOT / "tests").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            if any(name.startswith("wheelload.studies.commands") for name in names):
                offending.append(str(path.relative_to(ROOT)))
                break
    assert not offending, f"tests importing command modules: {offending}"


@pytest.mark.parametrize("constant", ["WHEELS", "GRAVITY", "AXLES", "SUSPENSION_TABLES"])
def test_a_shared_constant_is_defined_once(constant):
    """The wheel and axle orders, the suspension tables and gravity live in
    ``models/conventions.py``; everyone imports them."""
    homes = sorted(
        module
        for module, path in modules().items()
        for node in ast.parse(path.read_text()).body
        if isinstance(node, ast.Assign)
        and any(isinstance(t, ast.Name) and t.id == constant for t in node.targets)
    )
    assert homes == ["wheelload.models.conventions"]


def test_the_estimators_face_hands_out_every_name():
    import wheelload.estimators as face

    missing = [name for name in face.__all__ if not hasattr(face, name)]
    assert not missing, f"listed in wheelload.estimators.__all__ but not importable: {missing}"


def room(module: str) -> str:
    """The package (folder) a module stands in; a package's own ``__init__`` is its room."""
    path = modules()[module]
    return module if path.name == "__init__.py" else module.rpartition(".")[0]


def test_no_two_rooms_import_each_other():
    """Folders show the layers: between two sub-packages the arrows run one way only."""
    between = defaultdict(set)
    for module, targets in arrows().items():
        for target in targets:
            a, b = room(module), room(target)
            if a != b and not a.startswith(b + ".") and not b.startswith(a + "."):
                between[a, b].add(f"{module} -> {target}")
    both = sorted(
        f"{a} <-> {b}: {sorted(between[a, b])[0]}; {sorted(between[b, a])[0]}"
        for a, b in between
        if (b, a) in between and a < b
    )
    assert not both, "\n".join(both)


def layer(module: str) -> int:
    """Index in :data:`LAYERS` of the longest prefix naming ``module``."""
    best, found = -1, None
    for index, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if inside(module, (prefix,)) and len(prefix) > best:
                best, found = len(prefix), index
    assert found is not None, f"{module} is in no declared layer: add it to LAYERS"
    return found


def test_every_import_goes_down_the_declared_layers():
    """runtime < models < kernels < types < loops, logs < guards < kf < mhe, family,
    identification < codegen < the door (face, registry) < studies."""
    offending = sorted(
        f"{module} ({LAYERS[layer(module)][0]}) -> {target} ({LAYERS[layer(target)][0]})"
        for module, targets in arrows().items()
        for target in targets
        if layer(target) > layer(module)
    )
    assert not offending, "\n".join(offending)


def folder_graph() -> dict[str, set[str]]:
    """room -> the rooms its modules import (a package and its sub-packages are rooms
    of their own; a parent's ``__init__`` and its children are not an arrow)."""
    graph = defaultdict(set)
    for module, targets in arrows().items():
        for target in targets:
            a, b = room(module), room(target)
            if a != b and not a.startswith(b + ".") and not b.startswith(a + "."):
                graph[a].add(b)
    return {r: graph.get(r, set()) for r in {room(m) for m in modules()}}


def test_no_loop_between_folders():
    """Not only pairs: a circle through any number of folders fails."""
    found = circles(folder_graph())
    assert not found, "folder loops: " + "; ".join(" -> ".join(c) for c in found)
