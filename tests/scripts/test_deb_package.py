"""The Debian package as CPack builds it from this build folder (what `make deb` ships): its
control data, the files a rig needs at the paths Debian's tools look in, maintainer scripts that
parse, units that name the installed binaries, and nothing that points back at this machine.
Installing it into a fresh Debian root is `make deb`'s own check (scripts/check_deb.py)."""
import pathlib
import subprocess
import tomllib

import pytest

BINARIES = ["haptic-rt", "haptic-sim", "haptic-render", "haptic-trace", "haptic-status", "haptic-config",
            "haptic-fake-device", "haptic-device-probe"]
PYTHON_COMMANDS = list(tomllib.loads((pathlib.Path(__file__).parents[2] / "scripts/pyproject.toml").read_text())
                       ["project"]["scripts"])
UNITS = ["haptic-rt.service", "haptic-sim.service", "haptic-render.service", "haptic-trace.service",
         "haptic-dashboard.service", "hapfluid.target"]


@pytest.fixture(scope="module")
def deb(build_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("deb")
    r = subprocess.run(["cpack", "-G", "DEB", "-B", str(out)], cwd=build_dir, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    (package,) = out.glob("hapfluid_*.deb")
    tree = out / "tree"
    subprocess.run(["dpkg-deb", "-R", str(package), str(tree)], check=True)
    return package, tree


def field(package, name):
    return subprocess.run(["dpkg-deb", "-f", str(package), name], capture_output=True, text=True,
                          check=True).stdout.strip()


def test_the_package_depends_on_what_its_binaries_link_and_its_python_imports(deb):
    package, _ = deb
    assert field(package, "Package") == "hapfluid"
    depends = {d.split()[0] for d in field(package, "Depends").split(", ")}
    # by name: what the binaries load (Vulkan through volk) or run, and the Python package's imports
    assert {"libvulkan1", "systemd", "udev", "python3", "python3-numpy", "python3-matplotlib", "python3-can",
            "python3-tomli-w", "python3-aiohttp"} <= depends
    # from dpkg-shlibdeps: what the binaries link
    assert {"libc6", "libstdc++6", "libtomlplusplus3", "libusb-1.0-0", "libhidapi-hidraw0", "libsystemd0",
            "libglfw3", "libpng16-16"} <= depends
    assert "mesa-vulkan-drivers" in field(package, "Recommends")


def test_the_package_holds_what_a_rig_needs_where_debian_looks_for_it(deb, source_dir):
    _, tree = deb
    for b in BINARIES + PYTHON_COMMANDS:
        assert (tree / "usr/bin" / b).stat().st_mode & 0o111, b
    for u in UNITS:
        assert (tree / "usr/lib/systemd/system" / u).is_file(), u
    assert (tree / "usr/lib/sysusers.d/hapfluid.conf").is_file()
    assert (tree / "usr/lib/udev/rules.d/70-hapfluid.rules").is_file()
    assert (tree / "etc/hapfluid/hapfluid.env").is_file()
    assert (tree / "DEBIAN/conffiles").read_text().split() == ["/etc/hapfluid/hapfluid.env"]
    shipped = {p.name for p in (tree / "usr/share/hapfluid/scenes").glob("*.toml")}
    assert shipped == {p.name for p in (source_dir / "config/scenes").glob("*.toml")}
    assert (tree / "usr/share/hapfluid/rigs/fake_single.toml").is_file()
    assert (tree / "usr/share/hapfluid/hapfluid.dbc").is_file()
    for doc in ["README.md", "rig-setup.md", "architecture.md", "config-reference.md"]:
        assert (tree / "usr/share/doc/hapfluid" / doc).is_file(), doc


def test_the_python_package_is_debians_layout_with_its_entry_points(deb):
    _, tree = deb
    site = tree / "usr/lib/python3/dist-packages"
    assert (site / "hapfluid/launcher.py").is_file() and (site / "hapfluid/c_constants.py").is_file()
    assert (site / "hapfluid/dashboard/static/index.html").is_file()
    (dist_info,) = site.glob("hapfluid-*.dist-info")
    entry_points = (dist_info / "entry_points.txt").read_text()
    assert "[can.interface]" in entry_points and "hapfluid_loopback" in entry_points
    for c in PYTHON_COMMANDS:
        assert (tree / "usr/bin" / c).read_text().splitlines()[0] == "#!/usr/bin/python3", c
    assert not list(site.rglob("__pycache__"))


def test_units_name_the_installed_paths_and_nothing_points_back_at_this_build(deb, build_dir, source_dir):
    _, tree = deb
    for u in UNITS[:-1]:
        text = (tree / "usr/lib/systemd/system" / u).read_text()
        assert "/usr/bin/haptic-" in text and "/etc/hapfluid/" in text, u
        assert "/usr/local" not in text, u
    for path in tree.rglob("*"):
        if path.is_file() and not (path.stat().st_mode & 0o111 and path.parent.name == "bin"):
            data = path.read_bytes()
            for here in (str(build_dir), str(source_dir)):
                assert here.encode() not in data, f"{path.relative_to(tree)} names {here}"


def test_maintainer_scripts_parse_and_leave_the_services_disabled(deb):
    _, tree = deb
    for name in ["postinst", "prerm", "postrm"]:
        script = tree / "DEBIAN" / name
        assert script.stat().st_mode & 0o111, name
        assert subprocess.run(["sh", "-n", str(script)]).returncode == 0, name
        code = "\n".join(line for line in script.read_text().splitlines() if not line.lstrip().startswith("#"))
        assert "systemctl enable" not in code and "systemctl start" not in code, name
    assert "systemd-sysusers" in (tree / "DEBIAN/postinst").read_text()
    assert "disable" in (tree / "DEBIAN/prerm").read_text()
