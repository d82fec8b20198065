"""The launcher's Stack stops what it started with the SIGINT it sends, whatever signal
dispositions the launcher itself inherited."""
import signal
import subprocess
import sys

from hapfluid.launcher import Stack

# A service that says when it has started and waits for a signal; SIGINT's default ends it.
SLEEPER = "import signal; print('up', flush=True); signal.pause()"


def test_a_service_is_stopped_even_when_the_launcher_inherited_sigint_ignored(tmp_path):
    (tmp_path / "logs").mkdir()
    stack = Stack(tmp_path)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)  # as a background job of a shell
    try:
        p = stack.start("sleeper", [sys.executable, "-c", SLEEPER], stdout_pipe=True)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert p.stdout.readline().strip() == "up"
    # Ended by the SIGINT it was sent (it has no handler of its own): a stop, not a failure.
    assert stack.stop("sleeper", timeout_s=60) == 0
    assert "stopped by SIGINT while it started" in (tmp_path / "logs" / "sleeper.log").read_text()


def test_a_service_that_fails_on_its_own_is_reported(tmp_path):
    (tmp_path / "logs").mkdir()
    stack = Stack(tmp_path)
    p = stack.start("failing", [sys.executable, "-c", "import sys; sys.exit(3)"])
    p.wait(timeout=60)
    assert stack.stop("failing") == 3
