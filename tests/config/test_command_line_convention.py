"""The command-line convention (config/include/hapfluid/config/command_line.hpp) on every tool that
follows it: --help to stdout with exit 0, --version printing "<tool> <build id>", and a usage
error as one line on stderr naming the option, with exit 2."""
import re
import subprocess

import pytest

# tool -> a usage error and the option its one line must name
TOOLS = {
    "haptic-config": (["check", "--kind", "fish", "x.toml"], "--kind"),
    "haptic-trace": (["--out", "/nonexistent/trace.csv", "--duration", "soon"], "--duration"),
    "haptic-rt": (["--rig", "config/rigs/fake_single.toml", "--duration", "-1"], "--duration"),
    "haptic-device-probe": (["--address", "/tmp/nobody.sock", "--force", "1,2"], "--force"),
    "haptic-sim-standin": (["--shm-prefix", "nobody", "--pattern", "evil"], "--pattern"),
    "haptic-fake-device": (["--address", "/tmp/nobody.sock", "--node", "16"], "--node"),
    "haptic-sim": (["--live", "--scene", "x.toml", "--threads", "many"], "--threads"),
    "haptic-render": (["--headless", "--out", "/tmp/nobody-frames", "--camera-pitch", "90"], "--camera-pitch"),
}


def run(binary, tool, *args):
    return subprocess.run([str(binary(tool)), *args], capture_output=True, text=True, timeout=30)


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_help_goes_to_stdout_with_exit_0(binary, tool):
    result = run(binary, tool, "--help")
    assert result.returncode == 0 and result.stderr == ""
    assert f"Usage: {tool}" in result.stdout and "--version" in result.stdout


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_version_is_the_build_id_every_tool_shares(binary, tool):
    result = run(binary, tool, "--version")
    assert result.returncode == 0
    assert re.fullmatch(rf"{tool} \d+\.\d+\.\d+\+git\.\S+\n", result.stdout), result.stdout
    assert result.stdout.split()[1] == run(binary, "haptic-config", "--version").stdout.split()[1]


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_a_usage_error_is_one_line_naming_the_option_with_exit_2(binary, tool):
    args, option = TOOLS[tool]
    result = run(binary, tool, *args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{tool}: ") and option in lines[0], result.stderr


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_every_tool_takes_a_log_level_and_names_the_levels_when_it_is_wrong(binary, tool):
    assert "--log-level" in run(binary, tool, "--help").stdout
    result = run(binary, tool, "--log-level", "loud", *TOOLS[tool][0])
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{tool}: ") and "--log-level" in lines[0], result.stderr
    assert "error, warning, notice, info, debug" in lines[0] and '"loud"' in lines[0]


# tool -> an option with a valid value, given again before the usage error
REPEATED = {
    "haptic-config": ["check", "--rig", "config/rigs/fake_single.toml"],
    "haptic-trace": ["--out", "/nonexistent/other.csv"],
    "haptic-rt": ["--rig", "config/rigs/fake_dual.toml"],
    "haptic-device-probe": ["--address", "/tmp/other.sock"],
    "haptic-sim-standin": ["--shm-prefix", "other"],
    "haptic-fake-device": ["--address", "/tmp/other.sock"],
    "haptic-sim": ["--scene", "y.toml"],
    "haptic-render": ["--out", "/tmp/other-frames"],
}


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_an_option_given_twice_takes_its_last_value_on_every_tool(binary, tool):
    # Launchers append overrides to a base command line: a repeated option is not a usage error
    # (CLI11 would say "At Most 1 required"), so the line names the real one.
    args, option = TOOLS[tool]
    repeated = REPEATED[tool]
    if tool == "haptic-config":
        args = repeated + ["--rig", "config/rigs/fake_single.toml"] + args[1:]
    else:
        args = repeated + args
    result = run(binary, tool, *args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and option in lines[0] and "At Most" not in lines[0], result.stderr


# The benchmarks `make bench` runs (build/bench/): the same convention. bench -> a usage error
# and the option its one line must name.
BENCHES = {
    "bench_sim_cpu": ([], "--out"),
    "bench_sim_vulkan": ([], "--out"),
    "bench_live_backends": ([], "--out"),
    "bench_render": (["--frames", "0"], "--frames"),
    "firmware_bridge_loopback_ping_pong": (["--out", "x.json", "--iterations", "many"], "--iterations"),
}


def test_every_benchmark_is_checked(build_dir):
    built = {p.name for p in (build_dir / "bench").iterdir() if p.is_file()}
    assert built == set(BENCHES)


@pytest.mark.parametrize("bench", sorted(BENCHES))
def test_benchmarks_follow_the_convention(build_dir, bench):
    exe = str(build_dir / "bench" / bench)
    help_ = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=30)
    assert help_.returncode == 0 and help_.stderr == "" and f"Usage: {bench}" in help_.stdout
    version = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=30)
    assert re.fullmatch(rf"{bench} \d+\.\d+\.\d+\+git\.\S+\n", version.stdout), version.stdout
    args, option = BENCHES[bench]
    error = subprocess.run([exe, *args], capture_output=True, text=True, timeout=30)
    lines = error.stderr.strip().splitlines()
    assert error.returncode == 2
    assert len(lines) == 1 and lines[0].startswith(f"{bench}: ") and option in lines[0], error.stderr
