"""Deployment: `make install` puts systemd units, the sysusers file and the site settings under
the prefix, the units name the installed binaries, and systemd-analyze accepts them."""
import ctypes
import json
import os
import shutil
import subprocess
import sys

import pytest

UNITS = ("haptic-rt.service", "haptic-sim.service", "haptic-render.service", "haptic-trace.service",
         "haptic-dashboard.service", "hapfluid.target")


@pytest.mark.skipif(not shutil.which("systemd-analyze"), reason="systemd-analyze not installed")
def test_installed_units_pass_systemd_analyze_verify(build_dir, tmp_path):
    subprocess.run(["cmake", "--install", str(build_dir), "--prefix", str(tmp_path)], check=True,
                   capture_output=True, timeout=120)
    units = tmp_path / "lib" / "systemd" / "system"
    for name in UNITS:
        assert (units / name).exists(), name
    assert (tmp_path / "lib" / "sysusers.d" / "hapfluid.conf").exists()
    assert (tmp_path / "etc" / "hapfluid" / "hapfluid.env").exists()
    rt = (units / "haptic-rt.service").read_text()
    # The loop's unit: notify + watchdog, real-time limits, its own core, a dedicated user.
    for line in ("Type=notify", "WatchdogSec=", "LimitRTPRIO=", "LimitMEMLOCK=infinity", "CPUAffinity=1",
                 "User=hapfluid", "Restart=on-failure", f"ExecStart={tmp_path}/bin/haptic-rt "):
        assert line in rt, line
    assert "Type=notify" in (units / "haptic-sim.service").read_text()
    # The operator's page: a user of its own that only reads, no capabilities, nothing to write.
    dashboard = (units / "haptic-dashboard.service").read_text()
    for line in ("User=hapfluid-dashboard\n", "Group=hapfluid\n", "CapabilityBoundingSet=\n",
                 "ReadOnlyPaths=/dev/shm /var/lib/hapfluid\n", "NoNewPrivileges=yes\n", "--trust-user hapfluid ",
                 f"ExecStart={tmp_path}/bin/haptic-dashboard "):
        assert line in dashboard, line
    assert "u hapfluid-dashboard -:hapfluid" in (tmp_path / "lib" / "sysusers.d" / "hapfluid.conf").read_text()
    assert "haptic-dashboard.service" in (units / "hapfluid.target").read_text()
    result = subprocess.run(["systemd-analyze", "verify", *(str(units / n) for n in UNITS)],
                            capture_output=True, text=True, timeout=60)
    # verify exits 0 on some warnings (unknown keys are "ignored"): any message about our units fails.
    problems = [l for l in (result.stdout + result.stderr).splitlines() if str(units) in l or "hapfluid" in l]
    assert result.returncode == 0 and not problems, result.stdout + result.stderr


PR_SET_MDWE, PR_MDWE_REFUSE_EXEC_GAIN = 65, 1  # linux/prctl.h, Linux >= 6.3


def _deny_write_execute():
    """What MemoryDenyWriteExecute=yes does to the unit's process, without systemd: no mapping may
    gain PROT_EXEC (the kernel's own MDWE, which systemd's seccomp filter matches)."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_MDWE, PR_MDWE_REFUSE_EXEC_GAIN, 0, 0, 0) != 0:
        os._exit(97)


def _vulkan_batch(binary, source_dir, out, preexec=None):
    scene = source_dir / "tests" / "sim_gpu_vulkan" / "scenes" / "live_stirring_light.toml"
    return subprocess.run([str(binary("haptic-sim")), "--scene", str(scene), "--backend", "vulkan",
                           "--duration", "0.02", "--out", str(out)],
                          capture_output=True, text=True, timeout=120, preexec_fn=preexec)


def test_dashboard_unit_memory_policy_lets_the_page_serve(binary, source_dir):
    # MemoryDenyWriteExecute=yes in haptic-dashboard.service: Python and aiohttp must start under it.
    unit = (source_dir / "scripts" / "systemd" / "haptic-dashboard.service.in").read_text()
    assert any(l.strip() == "MemoryDenyWriteExecute=yes" for l in unit.splitlines())
    run = subprocess.run([sys.executable, "-c", "import aiohttp.web, hapfluid.dashboard.server"],
                         capture_output=True, text=True, timeout=60, preexec_fn=_deny_write_execute)
    if run.returncode == 97:
        pytest.skip("this kernel has no PR_SET_MDWE (Linux < 6.3)")
    assert run.returncode == 0, run.stderr[-2000:]


def test_sim_unit_memory_policy_lets_the_vulkan_backend_run(binary, source_dir, tmp_path):
    # The shipped unit's hardening must not kill the service it hardens: lavapipe JIT-compiles the
    # shaders into executable host memory, which MemoryDenyWriteExecute=yes forbids.
    unit = (source_dir / "scripts" / "systemd" / "haptic-sim.service.in").read_text()
    denies = any(l.strip() == "MemoryDenyWriteExecute=yes" for l in unit.splitlines())
    run = _vulkan_batch(binary, source_dir, tmp_path / "unit_policy", _deny_write_execute if denies else None)
    assert run.returncode == 0, f"haptic-sim --backend vulkan under haptic-sim.service's memory policy: " \
                                f"exit {run.returncode}\n{run.stderr[-2000:]}"
    device = json.loads((tmp_path / "unit_policy" / "stats.json").read_text()).get("device", {})
    if device.get("type", "").lower() != "cpu":
        return  # a GPU's driver compiles for the GPU: the control below is about lavapipe
    # Control: the policy really does break lavapipe here, so the run above proves something.
    denied = _vulkan_batch(binary, source_dir, tmp_path / "denied", _deny_write_execute)
    if denied.returncode == 97:
        pytest.skip("this kernel has no PR_SET_MDWE (Linux < 6.3): the control cannot run")
    assert denied.returncode != 0, "lavapipe ran under PR_SET_MDWE: the unit could deny write+execute again"
