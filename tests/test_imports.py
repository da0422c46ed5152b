"""The package is built in floors: a module imports only from its own floor or below, and no
import circle exists. Imports inside functions count too (a lazy import is still a dependency).

A new module must be placed on a floor here; the test fails until it is.
"""

from __future__ import annotations

import ast

from conftest import ROOT

#: Lowest first. Within a floor, imports are allowed as long as they form no circle.
FLOORS: tuple[tuple[str, ...], ...] = (
    # foundations: no knowledge of mechanisms
    ("errors", "vectors", "solver", "templating", "levels", "paths", "codegen.routines"),
    ("expressions", "codegen.literals", "codegen.runtime"),
    # the hinge models and their special functions
    ("special.registry", "special.kernels", "special.elastica", "special"),
    ("hinge_models",),
    # the mechanism, its graph and its kinematics (the paper's sections 2 to 5)
    ("mechanism",),
    ("structure",),
    ("kinematics", "reports"),
    ("rigid", "loop_equations"),
    ("analysis",),
    ("variants", "sensitivity"),
    # the physical levels: plate stiffness, the loaded level's derivation, the elastica solver
    ("physics.stiffness", "physics.beamcolumn", "physics.arith", "physics.result"),
    ("physics.elastica", "physics.statics", "pruning"),
    ("physics.equilibrium",),
    # code generation: the plan, then each backend's printer and kernels, then the backends
    ("codegen.derivation", "codegen.plan"),
    ("codegen.backends.c.printer", "codegen.backends.c.kernels",
     "codegen.backends.numpy.printer", "codegen.backends.numpy.kernels",
     "codegen.backends.latex.text", "codegen.backends.latex.figures"),
    ("codegen.backends.common",),
    ("codegen.backends.c.backend", "codegen.backends.numpy.backend",
     "codegen.backends.latex.report"),
    # numbers and commands
    ("evaluation",),
    ("compiled",),
    ("variation", "tolerance", "tradeoff", "sweep"),
    ("derive",),
    ("scene",),
    ("",),                                  # the package itself: symkin.load, analyze, ...
    # the finite-element check: a client of the package's public API (docs/fea.md)
    ("fea._symkin",),
    ("fea.deck", "fea.ccx"),
    ("fea",),
    ("fea.command",),
    ("cli", "__main__"),
)
#: Packages whose __init__ only documents them (no imports): no floor needed.
DOC_ONLY = ("physics", "codegen", "codegen.backends", "codegen.backends.c",
            "codegen.backends.numpy", "codegen.backends.latex")


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
                base = package[:len(package) - node.level + 1]
                target = ".".join([*base, *([node.module] if node.module else [])])
            elif (node.module or "").split(".")[0] == "symkin":
                target = node.module[len("symkin."):] if "." in node.module else ""
            else:
                continue
            for alias in node.names:
                full = f"{target}.{alias.name}".lstrip(".")
                found.add(full if full in known else target)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "symkin":
                    found.add(alias.name[len("symkin."):] if "." in alias.name else "")
    return found - {name}


def _is_package(name: str) -> bool:
    return (ROOT / "symkin" / name.replace(".", "/") / "__init__.py").exists()


def graph() -> dict[str, set[str]]:
    trees = modules()
    return {name: imports(name, tree, set(trees)) for name, tree in trees.items()}


def test_every_module_has_a_floor():
    floor_of = {m for floor in FLOORS for m in floor}
    missing = sorted(set(graph()) - floor_of - set(DOC_ONLY))
    assert not missing, f"put these modules on a floor in tests/test_imports.py: {missing}"
    for name in DOC_ONLY:
        assert not graph()[name], f"{name} imports something: give it a floor"


def test_no_upward_import():
    level = {m: k for k, floor in enumerate(FLOORS) for m in floor}
    upward = [f"{name or 'symkin'} imports {target or 'symkin'}"
              for name, targets in graph().items() for target in targets
              if name in level and level.get(target, -1) > level[name]]
    assert not upward, "upward imports:\n" + "\n".join(sorted(upward))


def test_no_import_circle():
    edges = graph()
    state: dict[str, int] = {}          # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
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
    assert "codegen.plan" in edges["evaluation"]            # imported inside a function
    assert "special.registry" in edges["special.kernels"]   # from .registry import ...
    assert "analysis" in edges["codegen.plan"]              # from ..analysis import ...
    assert "hinge_models" in edges["mechanism"]


def test_the_backends_read_the_plan_only():
    """The emitters take everything from a Plan: no backend reaches back into the derivation."""
    derivation_floors = {"mechanism", "structure", "kinematics", "rigid", "loop_equations",
                         "analysis", "hinge_models", "variants", "evaluation"}
    reach = [f"{name} imports {target}" for name, targets in graph().items()
             if name.startswith("codegen.backends") for target in targets
             if target in derivation_floors]
    assert not reach, "\n".join(sorted(reach))
