"""The package is built in floors: a module imports only from its own floor or below, and no
import circle exists. Imports inside functions count too (a lazy import is still a dependency).

A new module must be placed on a floor here; the test fails until it is.
"""

from __future__ import annotations

import ast
import functools

from conftest import ROOT

#: The subpackages, lowest first: a module imports only from its own package or from packages on
#: floors below it (docs/architecture.md draws them). Within a package, imports are free as long
#: as they form no circle. "" is the package itself (symkin.load, analyze, ...).
FLOORS: tuple[tuple[str, ...], ...] = (
    ("core",),  # errors, vectors, the level table, solver settings, file checks
    ("model",),  # expressions, hinge models and special functions, the file reader
    ("graph",),  # labeling, I, Φ, Ψ; pruning
    ("kinematics",),  # the paper's sections 3-5: positions, dyads, loop equations, deviation
    ("physics",),  # stiffness, loads, the physical levels
    ("codegen",),  # the plan, the backends (C, numpy), building and loading
    ("report",),  # the LaTeX report: reads a plan, its numpy module's and equilibrium's results
    ("studies",),  # evaluation, compiled evaluators, derive, tradeoff, tolerance, sweep, scene
    ("",),
    ("fea",),  # the CalculiX model of a mechanism: a client of the public API
    ("cli", "__main__"),
)
#: Packages whose __init__ only documents them (no imports): no floor of their own needed.
DOC_ONLY = (
    "core",
    "model",
    "graph",
    "kinematics",
    "physics",
    "codegen",
    "codegen.backends",
    "codegen.backends.c",
    "codegen.backends.numpy",
    "report",
    "studies",
)


def package(module: str) -> str:
    """The floor a module sits on: its top-level subpackage ('' for symkin itself)."""
    return "__main__" if module == "__main__" else module.split(".")[0]


def modules() -> dict[str, ast.Module]:
    """Every module of symkin by its name relative to the package ('' for symkin itself)."""
    out = {}
    for path in sorted((ROOT / "symkin").rglob("*.py")):
        parts = list(path.relative_to(ROOT / "symkin").with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = ast.parse(path.read_text(encoding="utf-8"))
    return out


def imports(name: str, tree: ast.Module, known: set[str]) -> set[str]:
    """The symkin modules `name` imports (a package when no module of that name exists)."""
    parts = name.split(".") if name else []
    package = parts if _is_package(name) else parts[:-1]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                target = ".".join([*base, *([node.module] if node.module else [])])
            elif (node.module or "").split(".")[0] == "symkin":
                target = node.module[len("symkin.") :] if "." in node.module else ""
            else:
                continue
            for alias in node.names:
                full = f"{target}.{alias.name}".lstrip(".")
                found.add(full if full in known else target)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "symkin":
                    found.add(alias.name[len("symkin.") :] if "." in alias.name else "")
    return found - {name}


def _is_package(name: str) -> bool:
    return (ROOT / "symkin" / name.replace(".", "/") / "__init__.py").exists()


@functools.cache
def graph() -> dict[str, set[str]]:
    """module -> the modules it imports (parsed once per run: every test reads it)."""
    trees = modules()
    return {name: imports(name, tree, set(trees)) for name, tree in trees.items()}


def test_every_module_has_a_floor():
    floor_of = {m for floor in FLOORS for m in floor}
    missing = sorted(m for m in graph() if package(m) not in floor_of)
    assert not missing, f"put these packages on a floor in tests/test_imports.py: {missing}"
    for name in DOC_ONLY:
        assert not graph()[name], f"{name}/__init__.py imports something: document it only"


def test_no_upward_import():
    level = {m: k for k, floor in enumerate(FLOORS) for m in floor}
    upward = [
        f"{name or 'symkin'} imports {target or 'symkin'}"
        for name, targets in graph().items()
        for target in targets
        if level.get(package(target), -1) > level[package(name)]
    ]
    assert not upward, "upward imports:\n" + "\n".join(sorted(upward))


def test_no_import_circle():
    edges = graph()
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == 1:
                return path[path.index(nxt) :] + [nxt]
            if nxt not in state:
                cycle = visit(nxt)
                if cycle:
                    return cycle
        path.pop()
        state[node] = 2
        return None

    for node in sorted(edges):
        if node not in state:
            cycle = visit(node)
            assert cycle is None, "import circle: " + " -> ".join(c or "symkin" for c in cycle)


def test_the_check_sees_lazy_and_relative_imports():
    """The parser finds what the package really imports, inside functions too."""
    edges = graph()
    assert "kinematics.sensitivity" in edges["studies.mpmath_sensitivity"]  # inside a function
    assert "model.special.registry" in edges["model.special.kernels"]  # from .registry import
    assert "kinematics.analysis" in edges["codegen.plan"]  # from ..kinematics...
    assert "model.hinges" in edges["model.mechanism"]
    assert "model.entry_checks" in edges["model.hinge_entries"]  # from .entry_checks import


def test_the_backends_read_the_plan_only():
    """The emitters take everything from a Plan: no backend, nor the report, reaches back into
    the derivation."""
    derivation = (
        *(f"model.{m}" for m in ("entries", "closure", "mechanism", "entry_checks")),
        *(f"model.{m}" for m in ("hinge_entries", "reader", "hinges")),
        "graph",
        "kinematics",
        "studies",
    )
    reach = [
        f"{name} imports {target}"
        for name, targets in graph().items()
        if name.startswith(("codegen.backends", "report"))
        for target in targets
        if target.startswith(derivation)
    ]
    assert not reach, "\n".join(sorted(reach))
