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
        "symkin.templates": [
            "**/*.j2",
            "*/runtime.c",
            "*/runtime.py",
            "*/actuators.c",
            "*/actuators.py",
            "*/reduced.c",
            "*/reduced.py",
            "*/reduced_sens.c",
            "*/reduced_sens.py",
            "*/reduced_report.c",
            "*/reduced_report.py",
            "*/reduced_actuators.py",
        ]
    },
)
