"""The package's layers (see src/fmu_components/__init__.py): every import, lazy ones
included, goes to the module's own layer or one below it, and no modules import each other
in a circle."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "fmu_components"
# Lower number, lower layer. The package root and errors are below everything.
LAYERS = {"": 0, "errors": 0, "runtime": 1, "coupling": 1, "export": 2, "lab": 3,
          "verification": 4, "commands": 5, "cli": 6, "__main__": 6}


def module_name(path):
    parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(["fmu_components", *parts])


def layer_of(module):
    head = module.split(".")[1] if "." in module else ""
    return LAYERS[head]


def imports_of(path):
    """The fmu_components modules a file imports, anywhere in it."""
    own = module_name(path)
    package = own if path.name == "__init__.py" else own.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("fmu_components")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("fmu_components"):
                continue
            # "from package import module" names a module; "from module import name" not.
            for alias in node.names:
                candidate = f"{target}.{alias.name}"
                is_module = (PACKAGE.parent / Path(*candidate.split("."))).with_suffix(".py")
                found.add(candidate if is_module.exists() else target)
    return found


MODULES = {module_name(p): p for p in PACKAGE.rglob("*.py")}


def test_the_layers_are_the_ones_documented():
    heads = {m.split(".")[1] for m in MODULES if "." in m}
    assert heads == set(LAYERS) - {""}


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_go_down_or_across_never_up(module):
    upward = sorted(i for i in imports_of(MODULES[module]) if layer_of(i) > layer_of(module))
    assert not upward, f"{module} imports from a higher layer: {upward}"


def test_no_module_imports_itself_through_others():
    graph = {m: {i for i in imports_of(p) if i in MODULES and i != m} for m, p in MODULES.items()}
    # Depth-first search for a back edge.
    state, path = {}, []

    def visit(module):
        state[module] = "open"
        path.append(module)
        for target in graph[module]:
            if state.get(target) == "open":
                cycle = path[path.index(target):] + [target]
                pytest.fail("circle: " + " -> ".join(cycle))
            if target not in state:
                visit(target)
        state[module] = "done"
        path.pop()

    for module in sorted(graph):
        if module not in state:
            visit(module)


LIBRARIES = ("runtime", "coupling", "export", "lab", "verification")


def test_the_libraries_never_read_the_command_line():
    """lab/, verification/ and the layers below are libraries a user imports: the command
    line (argparse, sys.argv) is the commands layer's alone."""
    readers = []
    for module, path in sorted(MODULES.items()):
        if "." not in module or module.split(".")[1] not in LIBRARIES:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(n.split(".")[0] == "argparse" for n in names) or (
                    isinstance(node, ast.Attribute) and node.attr == "argv"):
                readers.append(f"{module} line {node.lineno}")
    assert not readers, f"the command line read below the commands layer: {readers}"
