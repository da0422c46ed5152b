"""The Jinja2 environment every emitter and report shares (templates ship in the wheel), and the
runtimes the generated files hold (docs/runtime.md)."""

from __future__ import annotations

import hashlib
import re
from collections.abc import Iterable
from functools import cache
from importlib import resources
from importlib.resources.abc import Traversable

import jinja2

#: Jinja delimiters for LaTeX templates (SymForce style), so TeX's braces never clash with Jinja's.
LATEX_DELIMITERS = {
    "block_start_string": r"\BLOCK{",
    "block_end_string": "}",
    "variable_start_string": r"\VAR{",
    "variable_end_string": "}",
    "comment_start_string": r"\#{",
    "comment_end_string": "}",
}


@cache
def environment(latex: bool = False) -> jinja2.Environment:
    """Strict environment over the packaged templates: a missing variable is an error, not ''.
    `latex=True` uses the \\VAR{...} / \\BLOCK{...} delimiters of the LaTeX templates."""
    root = resources.files("symkin.templates")
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(root)),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
        **(LATEX_DELIMITERS if latex else {}),
    )
    # Names from a mechanism file reach generated code only through these escaping filters.
    env.filters["pyrepr"] = repr
    env.filters["cstring"] = c_string
    env.filters["notch_grid"] = notch_grid
    env.globals["runtime"] = runtime
    env.globals["shared"] = shared
    return env


@cache
def digest() -> str:
    """The sha256 of every packaged template and runtime (names and bytes, as on disk when first
    asked) and of Jinja2's version: what an emitted text is made of besides its plan
    (symkin.codegen.pipeline.emit)."""
    h = hashlib.sha256(f"jinja2 {jinja2.__version__}\0".encode())

    def walk(folder: Traversable, prefix: str) -> None:
        for entry in sorted(folder.iterdir(), key=lambda e: e.name):
            if entry.is_dir():
                if entry.name != "__pycache__":
                    walk(entry, f"{prefix}{entry.name}/")
            else:
                h.update(f"{prefix}{entry.name}".encode() + b"\0" + entry.read_bytes() + b"\0")

    walk(resources.files("symkin.templates"), "")
    for module in SHARED:
        h.update(f"{module}\0".encode() + _shared_file(module).read_bytes() + b"\0")
    return h.hexdigest()


#: A runtime file's marker line: what follows it is what every generated file holds.
RUNTIME_MARKER = "symkin runtime: every generated"
#: The conditionals of the C runtime's optional sections (docs/runtime.md).
_IF = re.compile(r"#\s*if\s+(defined\(\w+\)(?:\s*\|\|\s*defined\(\w+\))*)\s*$")


def runtime(path: str, features: Iterable[str] | None = ()) -> str:
    """The text a generated file holds of the runtime `path` (under templates/:
    c/runtime.c, numpy/runtime.py): everything after its marker line, verbatim but for its
    optional sections, resolved for `features` as the C preprocessor would with those macros
    defined (None: kept as they are). What comes before the marker (the includes or imports, the
    notes on testing it on its own) is for the file alone."""
    return _runtime(path, None if features is None else frozenset(features))


@cache
def _runtime(path: str, features: frozenset[str] | None) -> str:
    text = resources.files("symkin.templates").joinpath(path).read_text()
    _, marker, body = text.partition(RUNTIME_MARKER)
    if not marker:
        raise ValueError(f"templates/{path} has no line '{RUNTIME_MARKER} ...'")
    body = body.partition("\n")[2].lstrip("\n")
    return body if features is None or not path.endswith(".c") else _sections(body, features)


#: The package's modules whose text the generated numpy modules hold below their marker line:
#: the algorithms the Python path runs too, written once (docs/runtime.md).
SHARED = (
    "symkin.kinematics.loop_newton",
    "symkin.physics.reduced_rates",
    "symkin.physics.reduced_solver",
    "symkin.physics.stiffness_rule",
    "symkin.studies.stroke_solver",
)


def _shared_file(module: str) -> Traversable:
    package, _, name = module.rpartition(".")
    return resources.files(package).joinpath(f"{name}.py")


def shared(module: str) -> str:
    """The text a generated numpy module holds of the package's module `module` (one of
    SHARED): everything after its marker line, verbatim, as `runtime` gives a runtime's."""
    if module not in SHARED:
        raise ValueError(f"{module} is not one of the shared modules {SHARED}")
    return _shared(module)


@cache
def _shared(module: str) -> str:
    text = _shared_file(module).read_text()
    _, marker, body = text.partition(RUNTIME_MARKER)
    if not marker:
        raise ValueError(f"{module} has no line '{RUNTIME_MARKER} ...'")
    return body.partition("\n")[2].lstrip("\n")


def _sections(text: str, features: frozenset[str]) -> str:
    """`text` with its `#if defined(A) || defined(B) ...`, `#else`, `#endif` sections resolved:
    a section is kept when one of its macros is in `features`, its #else part otherwise."""
    out: list[str] = []
    kept: list[bool] = []  # per open section: whether its current part is kept
    for line in text.splitlines(keepends=True):
        directive = line.strip()
        if directive.startswith(("#if", "#elif")):
            condition = _IF.fullmatch(directive)
            if condition is None:
                raise ValueError(f"runtime: only '#if defined(X) || ...' is resolved: {line!r}")
            kept.append(any(m in features for m in re.findall(r"\((\w+)\)", directive)))
        elif directive == "#else":
            kept[-1] = not kept[-1]
        elif directive == "#endif":
            kept.pop()
        elif all(kept):
            out.append(line)
    if kept:
        raise ValueError("runtime: a section is not closed")
    return "".join(out)


def c_string(text: str) -> str:
    """A C string literal for any text: printable ASCII kept, everything else escaped."""
    out = []
    for byte in text.encode("utf-8"):
        ch = chr(byte)
        if ch in '"\\?':
            out.append("\\" + ch)
        elif 32 <= byte < 127:
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def notch_grid(table: Iterable[tuple[str, Iterable[float]]]) -> str:
    """A notch's stress grid (symkin.codegen.loaded.NotchPlate.grid) as a numpy module's dict of
    float arrays: every sample by repr, so the module shoots the Python level's float grid."""
    items = ", ".join(
        f"{key!r}: numpy.array([{', '.join(repr(float(v)) for v in values)}])"
        for key, values in table
    )
    return "{" + items + "}"


def render(template: str, **context: object) -> str:
    """Render `template` (a path under templates/) with `context`."""
    return environment().get_template(template).render(**context)
