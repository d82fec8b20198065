"""Fixtures of the script tests: a script of scripts/ imported as a module."""
import importlib.util
import sys

import pytest


@pytest.fixture(scope="session")
def script(source_dir):
    """script("scenario_checks") -> scripts/scenario_checks.py as a module (its own imports resolve in scripts/)."""
    scripts = str(source_dir / "scripts")
    if scripts not in sys.path:
        sys.path.insert(0, scripts)

    def load(name):
        spec = importlib.util.spec_from_file_location(name, source_dir / "scripts" / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    return load
