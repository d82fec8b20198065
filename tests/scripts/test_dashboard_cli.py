"""haptic-dashboard's command line: a bad rig file, address or rate is refused before anything is
served, naming the file, the key and the value."""
import signal
import subprocess
import sys

import pytest


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


@pytest.mark.parametrize("inherited", ["default", "ignored"])
@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_a_stop_while_it_starts_ends_it_quietly(tmp_path, inherited, stop):
    # The launcher stops a short run's services as soon as the run ends, and on a loaded machine
    # the page's server may still be importing then. A shell's background job inherits SIGINT
    # ignored; a stop in that window was lost and the server ran on until killed. The stop is
    # sent once the command has said it is starting (an event), while its imports go on.
    ignore = (lambda: signal.signal(signal.SIGINT, signal.SIG_IGN)) if inherited == "ignored" else None
    p = subprocess.Popen([sys.executable, "-m", "hapfluid.dashboard", "--shm-prefix", f"nostack-{tmp_path.name}",
                          "--listen", "127.0.0.1:0"], stderr=subprocess.PIPE, text=True, preexec_fn=ignore)
    try:
        assert p.stderr.readline().strip() == "haptic-dashboard: starting"
        p.send_signal(stop)
        err = p.stderr.read()  # to its end: the process has closed stderr, it exits
        assert p.wait(timeout=60) == 0, err
        assert "Traceback" not in err, err
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
