"""Starting haptic-fake-device and haptic-device-probe as separate processes for the tests."""
import json
import subprocess
import time


class FakeDevice:
    """A running haptic-fake-device; use as a context manager. Stops it and reads its summary."""

    def __init__(self, binary, socket, *args, duration=3.0):
        self.cmd = [str(binary), "--address", str(socket), "--duration", str(duration), *map(str, args)]
        self.summary = None

    def __enter__(self):
        self.proc = subprocess.Popen(self.cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()  # "haptic-fake-device: ready on ..." once the bus is bound
        if "ready" not in line:
            self.proc.kill()
            raise RuntimeError(f"fake device did not start: {line}{self.proc.stderr.read()}")
        return self

    def finish(self, timeout=10):
        out, err = self.proc.communicate(timeout=timeout)
        self.stderr = err
        assert self.proc.returncode == 0, err
        self.summary = json.loads(out.strip().splitlines()[-1])
        return self.summary

    def __exit__(self, *exc):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.finish(timeout=10)
            except Exception:
                self.proc.kill()
        return False


def probe(binary, socket, *args, check=True):
    """Runs haptic-device-probe to completion; returns its JSON report."""
    result = subprocess.run([str(binary), "--transport", "loopback", "--address", str(socket), *map(str, args)],
                            capture_output=True, text=True, timeout=30)
    if check:
        assert result.returncode == 0, result.stderr
        return json.loads(result.stdout)
    return result


def wait_for(predicate, timeout=5.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.01)
    return False
