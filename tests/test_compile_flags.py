"""The generated C under the flags users get (-O2) and under SYMKIN_CFLAGS (docs/cli.md,
"Compiler flags"): the suite compiles with -O0 to save time, so here every example's C as
`derive` writes it (generated/) is compiled with the defaults, -Werror included, and must give
the -O0 build's numbers at every level it holds."""

from __future__ import annotations

import os
import re
import subprocess

import numpy as np
import pytest
from conftest import EXAMPLES, ROOT
from evaluators import require_compiler

from symkin.cli import main
from symkin.codegen import toolchain
from symkin.core import levels

NAMES = sorted(p.stem for p in EXAMPLES.glob("*.toml"))


def _sizes(header: str, name: str) -> dict[str, int]:
    return {
        k: int(re.search(rf"#define {name.upper()}_N_{k} (\d+)", header).group(1))
        for k in ("INPUTS", "PARAMS", "POINTS", "HINGES")
    }


def test_flags_are_appended_to_the_defaults(monkeypatch):
    monkeypatch.delenv("SYMKIN_CFLAGS", raising=False)
    cc = os.environ.get("CC", "cc")
    version = subprocess.run([cc, "--version"], capture_output=True, text=True).stdout
    gcc = "Free Software Foundation" in version and "clang" not in version.lower()
    base = (*toolchain.CFLAGS, *(("-fno-tree-dse", "-fno-schedule-insns2") if gcc else ()))
    assert toolchain.cflags() == base and "-O2" in toolchain.CFLAGS
    monkeypatch.setenv("SYMKIN_CFLAGS", "-O3  -march='native'")
    assert toolchain.cflags() == (*base, "-O3", "-march=native")


@pytest.mark.parametrize("name", NAMES)
def test_every_example_compiles_with_the_default_flags_as_at_O0(name, monkeypatch):
    require_compiler()
    folder = ROOT / "generated" / name
    header = (folder / f"{name}.h").read_text()
    source = (folder / f"{name}.c").read_text()
    n = _sizes(header, name)
    monkeypatch.delenv("SYMKIN_CFLAGS", raising=False)
    default = toolchain.build(name, header, source)
    monkeypatch.setenv("SYMKIN_CFLAGS", "-O0")
    quick = toolchain.build(name, header, source)
    assert default != quick  # two libraries: the flags are in the hash
    libs = [
        toolchain.Library(path, name, n["INPUTS"], n["PARAMS"], n["POINTS"], n["HINGES"])
        for path in (default, quick)
    ]
    # small rotations of every input about the as-fabricated pose, a deterministic spread
    k = np.arange(1, 8)[:, None]
    inputs = 0.004 * np.sin(k * (1.0 + np.arange(n["INPUTS"]))[None, :])
    generated = re.search(r"only the levels generated: ([a-z_, ]+)\)", header).group(1)
    held = [levels.get(lv.strip()) for lv in generated.split(",")]
    assert "exact" in generated
    for lv in held:
        (s1, o1, a1), (s2, o2, a2) = (
            lib.evaluate_rows(inputs, None, lv.code, angles=True) for lib in libs
        )
        assert (s1 == 0).all(), (lv.name, s1)
        np.testing.assert_array_equal(s1, s2)
        np.testing.assert_allclose(o1, o2, rtol=1e-13, atol=1e-18, err_msg=lv.name)
        np.testing.assert_allclose(a1, a2, rtol=1e-13, atol=1e-18, err_msg=lv.name)


def test_flags_the_compiler_refuses_exit_2_naming_the_variable(tmp_path, monkeypatch, capsys):
    require_compiler()
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("SYMKIN_CFLAGS", "-fno-such-flag-symkin")
    code = main(["eval", str(EXAMPLES / "four_bar.toml"), "--backend", "c", "--input", "A0=0.1"])
    err = capsys.readouterr().err
    assert code == 2 and "SYMKIN_CFLAGS" in err and "-fno-such-flag-symkin" in err
    assert not list((tmp_path / "cache").glob("*.so"))
