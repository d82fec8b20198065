"""Shared pytest fixtures: where the build and the source tree are, and how to find binaries."""
import os
import pathlib

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parent.parent
BUILD_DIR = pathlib.Path(os.environ.get("HAPFLUID_BUILD", SOURCE_DIR / "build")).resolve()
SHARED_DIR = (SOURCE_DIR.parent / "shared").resolve()


@pytest.fixture(scope="session")
def source_dir() -> pathlib.Path:
    return SOURCE_DIR


@pytest.fixture(scope="session")
def build_dir() -> pathlib.Path:
    return BUILD_DIR


@pytest.fixture(scope="session")
def shared_dir() -> pathlib.Path:
    return SHARED_DIR


@pytest.fixture(scope="session")
def binary():
    """binary("haptic-config") -> path of a built program; fails clearly if it was not built."""

    def find(name: str) -> pathlib.Path:
        path = BUILD_DIR / "bin" / name
        if not path.exists():
            pytest.fail(f"{path} was not built: run `make` first")
        return path

    return find
