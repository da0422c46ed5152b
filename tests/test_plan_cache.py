"""Plans kept by content (symkin.codegen.plan_cache, docs/cli.md "Derivations are kept too"): a
second process reads the plan instead of deriving it and emits the same code; any change to the
file derives afresh; a planted or tampered plan is never unpickled; symkin.compile and
SYMKIN_PLAN_CACHE=off/memory write nothing."""

from __future__ import annotations

import hashlib
import os
import pickle
import stat
import subprocess
import sys
from pathlib import Path

import mechanisms as M
import pytest
import sympy as sp
from conftest import ROOT
from evaluators import GENERATED

import symkin
from symkin.codegen import pipeline, plan_cache

PARALLELOGRAM = ROOT / "tests" / "mechanisms" / "parallelogram.toml"

# derives (or reads) the parallelogram's plan and prints the digest of its C and numpy texts;
# with "forbid", deriving or emitting raises: the plan must come from the cache, its routines'
# operation counts (the headers print them) and its emitted texts with it; with "retemplate"
# the templates' digest differs: the plan is read, the texts emitted again (tallied)
SCRIPT = """
import hashlib, sys
import sympy
import symkin
from symkin.codegen import pipeline, templating
from symkin.codegen.backends.c import backend as c_backend
from symkin.codegen.backends.numpy import backend as numpy_backend
def boom(*args, **kwargs):
    raise AssertionError("derived, counted or emitted although the plan and texts were kept")
if sys.argv[2] in ("forbid", "retemplate"):
    pipeline.plan = boom
    sympy.count_ops = boom
if sys.argv[2] == "forbid":
    c_backend.emit = numpy_backend.emit = boom
if sys.argv[2] == "retemplate":
    templating.digest = lambda: "templates edited"
    for module in (c_backend, numpy_backend):
        def tallied(*args, _emit=module.emit, **kwargs):
            with open(sys.argv[3], "a") as tally:
                tally.write("emitted\\n")
            return _emit(*args, **kwargs)
        module.emit = tallied
if sys.argv[2] == "count":
    derive = pipeline.plan
    def counted(*args, **kwargs):
        with open(sys.argv[3], "a") as tally:
            tally.write("derived\\n")
        return derive(*args, **kwargs)
    pipeline.plan = counted
an = symkin.analyze(symkin.load(sys.argv[1]))
p = pipeline.plan_for(an)
texts = pipeline.emit(p, "c", "x") + pipeline.emit(p, "numpy", "x")
print(hashlib.sha256("\\0".join(texts).encode()).hexdigest())
"""


def run(cache: Path, mode: str, *args: str, **env: str) -> str:
    proc = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(PARALLELOGRAM), mode, *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, "SYMKIN_CACHE": str(cache), **env},
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout.strip()


def plans(cache: Path) -> list[str]:
    folder = cache / "plans"
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def test_a_second_process_reads_the_plan_and_emits_the_same_code(tmp_path):
    cache = tmp_path / "cache"
    first = run(cache, "derive", PYTHONHASHSEED="1")
    kept = plans(cache)
    # the plan, and the C and numpy texts emitted from it: each a pickle and its record
    assert len(kept) == 6
    assert {name.rsplit(".", 1)[1] for name in kept} == {"pickle", "sha256"}
    for name in kept:
        assert stat.S_IMODE((cache / "plans" / name).stat().st_mode) == 0o600
    # another process, another hash seed: nothing derived or emitted, the same code
    assert run(cache, "forbid", PYTHONHASHSEED="2") == first
    # edited templates: the plan is read back, its texts are emitted again, once per backend
    tally = tmp_path / "tally"
    assert run(cache, "retemplate", str(tally)) == first
    assert tally.read_text().split() == ["emitted", "emitted"]
    # the kept plan is the one a fresh derivation gives: the same texts without the cache
    assert run(tmp_path / "other", "derive", SYMKIN_PLAN_CACHE="off") == first
    assert plans(tmp_path / "other") == []


def test_memory_mode_writes_nothing(tmp_path):
    cache = tmp_path / "cache"
    run(cache, "derive", SYMKIN_PLAN_CACHE="memory")
    assert plans(cache) == []


def _key(text: str, **options) -> str | None:
    an = symkin.analyze(symkin.loads(text, "m.toml"))
    bound = pipeline._PLAN_SIGNATURE.bind(an, **options)
    bound.apply_defaults()
    return plan_cache.digest(an, {k: v for k, v in bound.arguments.items() if k != "analysis"})


def test_any_change_to_the_file_or_the_options_derives_afresh():
    text = PARALLELOGRAM.read_text()
    base = _key(text)
    assert base is not None and base == _key(text)
    changed = {
        "a digit of a parameter": text.replace("l = 5e-3", "l = 5.0000000001e-3"),
        "the thickness": text.replace("thickness = 0.15e-3", "thickness = 0.16e-3"),
        "a name": text.replace('"F1"', '"F9"'),
        "a comment only": text + "\n# a comment\n",
    }
    for what, other in changed.items():
        assert other != text or what == "a comment only", what
        key = _key(other)
        if what == "a comment only":
            assert key == base, "a comment changes nothing derived"
        else:
            assert key != base, what
    assert _key(text, sensitivity=False) != base
    assert _key(text, levels=("exact",)) != base


def test_the_digest_is_the_same_under_every_hash_seed(tmp_path):
    script = (
        "import sys; sys.path.insert(0, 'tests'); from test_plan_cache import _key, PARALLELOGRAM;"
        "print(_key(PARALLELOGRAM.read_text()))"
    )
    keys = {
        subprocess.run(
            [sys.executable, "-c", script],
            capture_output=True,
            text=True,
            cwd=ROOT,
            env={**os.environ, "PYTHONHASHSEED": seed},
            check=True,
            timeout=300,
        ).stdout.strip()
        for seed in ("0", "12345")
    }
    assert len(keys) == 1 and None not in keys


def test_what_the_digest_cannot_describe_is_derived_not_looked_up():
    an = symkin.analyze(symkin.load(PARALLELOGRAM))
    assert plan_cache.digest(an, {"strange": object()}) is None


class _Planted:
    """Unpickling it writes the marker: what a planted plan would do."""

    def __init__(self, marker: str) -> None:
        self.marker = marker

    def __reduce__(self):
        return (Path(self.marker).write_text, ("ran",))


@pytest.mark.parametrize("tamper", ["wrong record", "others can write it", "a link"])
def test_a_planted_plan_is_never_unpickled(tmp_path, tamper):
    folder = tmp_path / "plans"
    folder.mkdir(mode=0o700)
    key = "ab" * 32
    marker = tmp_path / "marker"
    data = pickle.dumps(_Planted(str(marker)))
    digest = hashlib.sha256(data).hexdigest()
    target, record = folder / f"{key}.pickle", folder / f"{key}.sha256"
    if tamper == "a link":
        elsewhere = tmp_path / "elsewhere.pickle"
        elsewhere.write_bytes(data)
        elsewhere.chmod(0o600)
        target.symlink_to(elsewhere)
    else:
        target.write_bytes(data)
        target.chmod(0o666 if tamper == "others can write it" else 0o600)
    record.write_text(f"{key}\n{'0' * 64 if tamper == 'wrong record' else digest}\n")
    record.chmod(0o600)
    assert plan_cache._read(folder, key, object) is None
    assert not marker.exists()


def test_compile_writes_no_plan(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path / "cache"))
    symkin.compile(PARALLELOGRAM, backend="numpy", levels=["exact"], sensitivity=False)
    assert plans(tmp_path / "cache") == []


def test_an_evaluation_reuses_a_plan_with_sensitivities_and_gives_the_same_numbers(monkeypatch):
    """evaluate (no sensitivities) takes the plan with sensitivities derived before; its numbers
    are those of the narrower plan's evaluators, bit for bit, in numpy and C."""
    from symkin.studies.evaluation import evaluate

    monkeypatch.setenv("SYMKIN_PLAN_CACHE", "off")  # nothing kept from other tests
    fresh = symkin.analyze(symkin.load(PARALLELOGRAM))
    narrow = pipeline.plan_for(fresh, sensitivity=False)
    assert pipeline.plan_covering(fresh, sensitivity=False) is narrow  # nothing wider yet
    want = {b: evaluate(fresh, {"F1": "0.03"}, "exact", backend=b) for b in GENERATED}
    monkeypatch.setenv("SYMKIN_PLAN_CACHE", "memory")
    an = symkin.analyze(symkin.load(PARALLELOGRAM))
    wide = pipeline.plan_for(an, sensitivity=True)
    assert pipeline.plan_covering(an, sensitivity=False) is wide
    exact = pipeline.plan_covering(an, sensitivity=False, levels=["exact"])
    assert exact is not wide  # other options: not served by the plan of every level
    # a plan of fewer levels serves an evaluation at one of them, not at another
    other = symkin.analyze(symkin.load(PARALLELOGRAM))
    only = pipeline.plan_for(other, sensitivity=False, levels=["exact"])
    assert pipeline.plan_covering(other, "exact", sensitivity=False) is only
    assert pipeline.plan_covering(other, "exact", sensitivity=True) is not only
    assert pipeline.plan_covering(other, "paper", sensitivity=False) is not only
    # another analysis of the same file finds it by content
    again = symkin.analyze(symkin.load(PARALLELOGRAM))
    assert pipeline.plan_covering(again, sensitivity=False) is wide
    for backend, w in want.items():
        got = evaluate(again, {"F1": "0.03"}, "exact", backend=backend)
        assert got.points == w.points, backend


def test_two_processes_at_once_derive_the_plan_once(tmp_path):
    """The second process waits for the first's plan (toolchain.exclusive) and reads it."""
    cache, tally = tmp_path / "cache", tmp_path / "tally"
    env = {**os.environ, "SYMKIN_CACHE": str(cache)}
    args = [sys.executable, "-c", SCRIPT, str(PARALLELOGRAM), "count", str(tally)]
    procs = [
        subprocess.Popen(args, cwd=ROOT, env=env, stdout=subprocess.PIPE, text=True)
        for _ in range(2)
    ]
    outs = [p.communicate(timeout=600)[0].strip() for p in procs]
    assert [p.returncode for p in procs] == [0, 0]
    assert outs[0] == outs[1] and len(outs[0]) == 64
    assert tally.read_text() == "derived\n"


def test_without_a_usable_lock_folder_the_body_runs_plainly(tmp_path, monkeypatch):
    """toolchain.exclusive on a cache folder others can write (no lock file is made there):
    the body runs unlocked, and its own error carries no trace of the refused folder."""
    from symkin.codegen import toolchain

    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    monkeypatch.setenv("SYMKIN_CACHE", str(shared))
    ran = []
    with pytest.raises(ValueError, match="body") as err, toolchain.exclusive("x"):
        ran.append(True)
        raise ValueError("body")
    assert ran == [True] and err.value.__context__ is None
    assert not (shared / "locks").exists()


def test_the_python_loaded_level_is_derived_once_per_file_content():
    """The loaded level's lambdified solvers (no pickle) are kept in memory by content: a
    second analysis of the same file finds them and gives the same numbers; another file (one
    plate thicker) derives its own."""
    from symkin.studies import physical

    text = PARALLELOGRAM.read_text()
    first = symkin.analyze(symkin.loads(text, "para.toml"))
    a = physical.reduced_equilibrium(first, {"F1": "0.05"})
    again = symkin.analyze(symkin.loads(text, "para.toml"))
    b = physical.reduced_equilibrium(again, {"F1": "0.05"})
    assert physical._REDUCED[again] is physical._REDUCED[first]
    assert a.deviations == b.deviations
    thicker = text.replace("thickness = 0.15e-3", "thickness = 0.16e-3", 1)
    other = symkin.analyze(symkin.loads(thicker, "para.toml"))
    c = physical.reduced_equilibrium(other, {"F1": "0.05"})
    assert physical._REDUCED[other] is not physical._REDUCED[first]
    assert c.deviations != a.deviations


def test_parameter_values_are_put_in_as_subs_puts_them():
    """expressions.substitute passes subs only an expression's own symbols (a file may have
    hundreds of parameters): the same value as subs with every parameter."""
    from symkin.model.expressions import substitute

    syms = sp.symbols("p0:400", positive=True)
    values = {s: sp.Rational(k + 1, 7) for k, s in enumerate(syms)}
    expr = sp.sqrt(syms[3] ** 2 + syms[250]) / syms[399] + sp.sin(syms[7])
    assert substitute(expr, values) == expr.subs(values)
    assert substitute("2", values) == 2


def test_notes_and_the_report_dress_one_derivation(monkeypatch):
    """A plan with notes (tolerance's chosen variant) or a report's statement is the plan
    without them, dressed: derived once, and what plan() derives with them, text for text."""
    monkeypatch.setenv("SYMKIN_PLAN_CACHE", "off")
    calls = []
    derive = pipeline.plan

    def counted(an, **options):
        calls.append(options)
        return derive(an, **options)

    monkeypatch.setattr(pipeline, "plan", counted)
    an = symkin.analyze(symkin.loads(M.FIVE_BAR))
    opts = {"levels": ("exact",), "fixed": {"O1": sp.Rational(1, 10)}}
    noted = pipeline.plan_for(an, notes=("Chosen: exact.",), **opts)
    reported = pipeline.plan_for(an, report=True, **opts)
    both = pipeline.plan_for(an, report=True, notes=("Chosen: exact.",), **opts)
    assert len(calls) == 1 and not calls[0]["notes"] and not calls[0]["report"]
    for got, options in (
        (noted, {"notes": ("Chosen: exact.",)}),
        (reported, {"report": True}),
        (both, {"report": True, "notes": ("Chosen: exact.",)}),
    ):
        want = derive(an, **opts, **options)
        # the fixed input's note after the asked ones, as plan() writes them
        assert got.notes == want.notes and len(want.notes) == len(options.get("notes", ())) + 1
        assert repr(got.derivation) == repr(want.derivation)
        assert (got.derivation is None) == ("report" not in options)
        for backend in GENERATED:
            assert pipeline.emit(got, backend, "x") == pipeline.emit(want, backend, "x")


def test_the_plate_relation_is_lambdified_once_per_process_and_module():
    """The plate relation and energy hold no mechanism's data: every Reduced shares them."""
    from symkin.physics import reduced
    from symkin.physics.plate_relation import relation
    from symkin.studies.configuration import parameter_values

    solvers = []
    for path in (PARALLELOGRAM, ROOT / "examples" / "four_bar.toml"):
        mech = symkin.load(path)
        solvers.append(reduced.Reduced(symkin.analyze(mech).kin, parameter_values(mech)))
    for key in ("plate4", "plate2", "energy"):
        assert solvers[0]._fn(key) is solvers[1]._fn(key)
    th, p, f, ea, es = sp.symbols("theta p f e_a e_s", real=True)
    point = {th: sp.Rational(3, 10), p: sp.Rational(1, 5), f: sp.Rational(-1, 7), ea: 0, es: 0}
    rel = relation(th, p, f, ea, es, 4)
    got = solvers[1]._fn("plate4")(*point.values())
    for g, want in zip(got[:3], (rel.along, rel.across, rel.omega)):
        assert abs(float(g) - float(want.subs(point).evalf(30))) <= 1e-15 * (1 + abs(float(g)))
