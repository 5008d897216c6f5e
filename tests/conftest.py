"""Fixtures shared by the test files."""

import importlib.util
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def load_file():
    """A function returning the module of a .py file of the repository, by its path from the root: tools/ and the
    benchmarks' build scripts are not packages."""

    def load(relative: str):
        path = ROOT / relative
        name = "repo_file_" + re.sub(r"\W", "_", relative)  # registered: a dataclass looks its module up by name
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        return module

    return load
