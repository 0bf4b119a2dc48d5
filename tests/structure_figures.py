"""The layout's figures, from the code's own imports: ``python3 tests/structure_figures.py``.

Modules, import arrows, loops between folders, integer indexes into the named layouts, the
estimators' face, functions over 80 lines and modules over 400 lines (tests not counted).
The rules these figures watch are tests in ``test_structure.py``.
"""

import ast
import re

from test_structure import arrows, circles, folder_graph, modules

#: A subscript of a layout vector by an integer literal (``tuning[0]``, ``tuned[2:5]``).
LAYOUT_INDEX = re.compile(r"\b(tuning|tuned)\[-?[0-9]")
LONG_FUNCTION = 80
LONG_MODULE = 400


def figures() -> dict[str, int]:
    paths = modules()
    sources = {name: path.read_text() for name, path in paths.items()}
    functions = [
        node
        for source in sources.values()
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
    ]
    face = __import__("wheelload.estimators", fromlist=["__all__"])
    return {
        "modules": len(paths),
        "import arrows": sum(len(targets) for targets in arrows().values()),
        "loops between folders": len(circles(folder_graph())),
        "integer indexes into layouts": sum(
            len(LAYOUT_INDEX.findall(source))
            for name, source in sources.items()
            if name.startswith(("wheelload.estimators", "wheelload.studies"))
        ),
        "names of the estimators' face": len(face.__all__),
        f"functions over {LONG_FUNCTION} lines": sum(
            node.end_lineno - node.lineno + 1 > LONG_FUNCTION for node in functions
        ),
        f"modules over {LONG_MODULE} lines": sum(
            len(source.splitlines()) > LONG_MODULE for source in sources.values()
        ),
    }


if __name__ == "__main__":
    for name, value in figures().items():
        print(f"{name:>32}: {value}")
