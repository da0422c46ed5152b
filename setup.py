"""Package discovery for setuptools: every package under symkin/ is found, not listed.

The Jinja templates and the runtimes the generated files hold (templates/c/runtime.c,
templates/numpy/runtime.py: docs/runtime.md) live in the top-level templates/ folder and ship
inside the wheel as the package symkin.templates (package_dir maps it), so a plain, non-editable
install finds them.
Everything else (metadata, dependencies, scripts) is in pyproject.toml.
"""

from setuptools import find_packages, setup

setup(
    packages=find_packages(include=["symkin", "symkin.*"]) + ["symkin.templates"],
    package_dir={"symkin.templates": "templates"},
    package_data={
        # every template and runtime under templates/ (a runtime left out here would only fail
        # a non-editable install: tests/test_packaging.py checks the wheel holds them all)
        "symkin.templates": ["**/*.j2", "*/*.c", "*/*.h", "*/*.py"]
    },
)
