"""Shared pytest fixtures: where the build and the source tree are, and how to find binaries; and
the `slow` marker that `make check` leaves out (`make test` runs everything)."""
import os
import pathlib

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parent.parent
BUILD_DIR = pathlib.Path(os.environ.get("HAPFLUID_BUILD", SOURCE_DIR / "build")).resolve()
SHARED_DIR = (SOURCE_DIR.parent / "shared").resolve()


# Folders whose every test runs the live stack, a QEMU guest or whole scenes: slow as a whole.
SLOW_FOLDERS = ("hil", "hil-kernel", "scenarios")


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: runs for seconds (live stack, QEMU, whole scenes); "
                                       "`make check` deselects it, `make test` runs it")


def pytest_collection_modifyitems(config, items):
    tests = SOURCE_DIR / "tests"
    for item in items:
        path = pathlib.Path(str(item.fspath)).resolve()
        if path.is_relative_to(tests) and path.relative_to(tests).parts[0] in SLOW_FOLDERS:
            item.add_marker(pytest.mark.slow)


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
