"""A built wheel, installed in a fresh venv, runs `symkin matrices` and finds its templates."""

from __future__ import annotations

import json
import subprocess
import sys
import venv

from conftest import EXAMPLES, ROOT


def test_wheel_installs_and_runs(tmp_path):
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps",
                    "-q", "-w", str(wheels)], check=True)
    wheel = next(wheels.glob("symkin-*.whl"))
    env_dir = tmp_path / "venv"
    # System site packages supply sympy/numpy/jinja2 without a download; symkin itself must
    # come from the wheel, which the venv's own site-packages puts first.
    venv.EnvBuilder(system_site_packages=True, with_pip=True).create(env_dir)
    py = env_dir / "bin" / "python"
    subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-deps", str(wheel)], check=True)
    where = subprocess.run([str(py), "-c", "import symkin, sys; print(symkin.__file__)"],
                           capture_output=True, text=True, check=True, cwd=tmp_path).stdout
    assert where.startswith(str(env_dir)), where
    out = subprocess.run([str(env_dir / "bin" / "symkin"), "matrices", "--json",
                          str(EXAMPLES / "four_bar.toml")],
                         capture_output=True, text=True, check=True, cwd=tmp_path).stdout
    assert json.loads(out)["loops"] == [[1, 1, -1, 1]]
    text = subprocess.run([str(env_dir / "bin" / "symkin"), "matrices",
                           str(EXAMPLES / "four_bar.toml")],
                          capture_output=True, text=True, check=True, cwd=tmp_path).stdout
    assert "incidence I" in text          # rendered from the packaged Jinja template
