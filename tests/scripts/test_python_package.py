"""The hapfluid Python package as the project venv holds it: this checkout's code, at the CMake
project's version, its commands on PATH in the venv, python-can finding its bus through the entry
point, and every installed distribution at the version scripts/constraints.txt pins."""
import pathlib
import re
import subprocess
import sys
import tomllib
from importlib import metadata

import hapfluid

norm = lambda name: re.sub(r"[-_.]+", "-", name).lower()  # noqa: E731  (PEP 503 names)


def pyproject(source_dir):
    return tomllib.loads((source_dir / "scripts" / "pyproject.toml").read_text())["project"]


def test_the_tests_import_this_checkouts_package_at_the_projects_version(source_dir):
    assert pathlib.Path(hapfluid.__file__).resolve().parent == source_dir / "scripts" / "hapfluid"
    cmake_version = re.search(r"project\(hapfluid VERSION (\S+)", (source_dir / "CMakeLists.txt").read_text()).group(1)
    assert pyproject(source_dir)["version"] == cmake_version
    assert hapfluid.__version__ == cmake_version


def test_every_command_is_installed_and_answers_help(source_dir):
    bin_dir = pathlib.Path(sys.executable).parent
    for command in pyproject(source_dir)["scripts"]:
        result = subprocess.run([str(bin_dir / command), "--help"], capture_output=True, text=True, timeout=60)
        assert result.returncode == 0, (command, result.stderr)
        assert result.stdout.startswith("usage: "), command
    launcher = subprocess.run([sys.executable, "-m", "hapfluid", "run", "--help"], capture_output=True, text=True,
                              timeout=60)
    assert launcher.returncode == 0 and "--scene" in launcher.stdout, launcher.stderr


def test_python_can_lists_the_loopback_bus_without_importing_hapfluid():
    # A fresh interpreter: python-can reads the entry points itself; nothing is patched into it.
    code = ("import sys, can; print(can.interfaces.BACKENDS['hapfluid_loopback']); "
            "print('hapfluid' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:2] == ["('hapfluid.proto.pycan_loopback', 'LoopbackBus')", "False"]


def test_every_installed_distribution_is_at_its_pinned_version(source_dir):
    pins = {}
    for line in (source_dir / "scripts" / "constraints.txt").read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            name, version = line.split("==")
            pins[norm(name)] = version.strip()
    # pip and setuptools come with the venv itself (python -m venv), not from our install; the
    # setuptools pin is for the isolated environment that builds the package.
    installed = {norm(d.metadata["Name"]): d.version for d in metadata.distributions()
                 if norm(d.metadata["Name"]) not in ("pip", "setuptools", "hapfluid")}
    unpinned = sorted(set(installed) - set(pins))
    assert not unpinned, f"installed without a pin in scripts/constraints.txt: {unpinned}"
    wrong = {n: (v, pins[n]) for n, v in installed.items() if n in pins and v != pins[n]}
    assert not wrong, f"installed (version, pin): {wrong}"
    # What the package asks for is pinned too, so a fresh venv resolves to the same set.
    spec = pyproject(source_dir)
    wanted = [*spec["dependencies"], *(r for extra in spec["optional-dependencies"].values() for r in extra)]
    assert all(norm(re.match(r"[A-Za-z0-9._-]+", r).group()) in pins for r in wanted)


def test_a_copy_outside_a_checkout_finds_data_by_hapfluid_root_or_writes_under_the_working_directory(source_dir,
                                                                                                    tmp_path):
    import shutil
    shutil.copytree(source_dir / "scripts" / "hapfluid", tmp_path / "site" / "hapfluid",
                    ignore=shutil.ignore_patterns("__pycache__"))
    code = "from hapfluid import paths; print(paths.ROOT); print(paths.SCENES); print(paths.DBC)"
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(tmp_path / "site")}
    named = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=tmp_path,
                           env={**env, "HAPFLUID_ROOT": str(source_dir)})
    assert named.returncode == 0, named.stderr
    assert named.stdout.split("\n")[:3] == [str(source_dir), str(source_dir / "config" / "scenes"),
                                            str(source_dir / "firmware_bridge" / "dbc" / "hapfluid.dbc")]
    alone = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=tmp_path,
                           env=env)
    assert alone.returncode == 0, alone.stderr
    root, scenes, dbc = alone.stdout.split("\n")[:3]
    assert root == str(tmp_path)  # outputs under the working directory, never in the install
    assert scenes.endswith("share/hapfluid/scenes") and dbc.endswith("share/hapfluid/hapfluid.dbc")
