"""Package discovery for setuptools: every package under symkin/ is found, not listed.

The Jinja templates and the runtimes the generated files hold (templates/c/runtime.c,
templates/numpy/runtime.py: docs/runtime.md) live in the top-level templates/ folder and ship
inside the wheel as the package symkin.templates (package_dir maps it), so a plain, non-editable
install finds them.
Everything else (metadata, dependencies, scripts) is in pyproject.toml.
"""

from pathlib import Path

from setuptools import find_packages, setup

# each language's folder is a package of its own (setuptools warns of, and will one day drop,
# a folder Python can import that is not listed)
LANGUAGES = sorted(
    p.name
    for p in Path(__file__).parent.joinpath("templates").iterdir()
    if p.is_dir() and p.name != "__pycache__"
)

setup(
    packages=find_packages(include=["symkin", "symkin.*"])
    + ["symkin.templates"]
    + [f"symkin.templates.{lang}" for lang in LANGUAGES],
    package_dir={"symkin.templates": "templates"},
    package_data={
        # every template and runtime under templates/ (a runtime left out here would only fail
        # a non-editable install: tests/test_packaging.py checks the wheel holds them all)
        f"symkin.templates.{lang}": ["*.j2", "*.c", "*.h", "*.py"]
        for lang in LANGUAGES
    },
)
