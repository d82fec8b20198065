"""Deployment: `make install` puts systemd units, the sysusers file and the site settings under
the prefix, the units name the installed binaries, and systemd-analyze accepts them."""
import shutil
import subprocess

import pytest

UNITS = ("haptic-rt.service", "haptic-sim.service", "haptic-render.service", "haptic-trace.service", "hapfluid.target")


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
    result = subprocess.run(["systemd-analyze", "verify", *(str(units / n) for n in UNITS)],
                            capture_output=True, text=True, timeout=60)
    # verify exits 0 on some warnings (unknown keys are "ignored"): any message about our units fails.
    problems = [l for l in (result.stdout + result.stderr).splitlines() if str(units) in l or "hapfluid" in l]
    assert result.returncode == 0 and not problems, result.stdout + result.stderr
