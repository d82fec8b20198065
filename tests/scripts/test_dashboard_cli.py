"""haptic-dashboard's command line: a bad rig file, address or rate is refused before anything is
served, naming the file, the key and the value."""
import subprocess
import sys


def dashboard(*args):
    return subprocess.run([sys.executable, "-m", "hapfluid.dashboard", *map(str, args)], capture_output=True,
                          text=True, timeout=60)


def test_bad_input_is_named_and_nothing_is_served(tmp_path):
    broken = tmp_path / "broken.toml"
    broken.write_text('name = "x"\n[dashboard\n')
    r = dashboard("--rig", broken)
    assert r.returncode == 2 and f"--rig {broken}" in r.stderr and "line 2" in r.stderr, r.stderr
    bad = tmp_path / "bad.toml"
    bad.write_text('[dashboard]\naddress = "nohost"\n')
    r = dashboard("--rig", bad)
    assert r.returncode != 0 and f"{bad}: dashboard.address = 'nohost': not HOST:PORT" in r.stderr, r.stderr
    r = dashboard("--listen", "127.0.0.1:99999")
    assert r.returncode != 0 and "--listen = '127.0.0.1:99999': not HOST:PORT" in r.stderr, r.stderr
    r = dashboard("--rate", "100")
    assert r.returncode == 2 and "--rate 100.0: must be in (0, 30]" in r.stderr, r.stderr
    r = dashboard("--status-binary", tmp_path / "nothing")
    assert r.returncode == 2 and "not an executable" in r.stderr, r.stderr
