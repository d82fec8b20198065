"""The host's hung-guest watchdog follows the guest's progress lines, not a fixed total."""
import importlib.util
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
_spec = importlib.util.spec_from_file_location("hil_driver", HERE / "hil.py")
hil = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(hil)


def test_a_slow_suite_that_keeps_progressing_is_never_killed():
    w = hil.ProgressWatchdog(start=0.0)
    now = 5.0
    for k in range(30):  # 30 tests of 50 s each: 25 min in all, far past any fixed total
        w.line(now, f"HIL-TEST [{k + 1}/30] t{k}: running (limit 90 s)")
        now += 50.0
        assert w.expired(now) is None
        w.line(now, f"HIL-TEST [{k + 1}/30] t{k}: PASS (50.0 s guest time)")
        now += 1.0
        assert w.expired(now) is None


def test_a_test_past_its_own_limit_and_grace_counts_as_hung():
    w = hil.ProgressWatchdog(start=0.0)
    w.line(10.0, "HIL-TEST [1/2] can: running (limit 40 s)")
    assert w.expired(10.0 + 40 + hil.TEST_GRACE_S - 0.1) is None
    why = w.expired(10.0 + 40 + hil.TEST_GRACE_S)
    assert why and "can to finish" in why


def test_a_guest_that_never_starts_a_test_or_never_powers_off_counts_as_hung():
    w = hil.ProgressWatchdog(start=0.0)
    assert "first test" in w.expired(hil.BOOT_LIMIT_S)
    w.line(1.0, "HIL-TEST [1/1] only: running (limit 20 s)")
    w.line(5.0, "HIL-TEST [1/1] only: FAIL (4.0 s guest time) - exit 1")
    assert w.expired(5.0 + hil.BETWEEN_LIMIT_S - 0.1) is None
    assert "power-off after only" in w.expired(5.0 + hil.BETWEEN_LIMIT_S)


def test_an_explicit_total_limit_still_applies():
    w = hil.ProgressWatchdog(start=0.0, total_limit_s=100.0)
    w.line(90.0, "HIL-TEST [1/1] only: running (limit 60 s)")
    assert "--timeout" in w.expired(100.0)
    assert w.seconds_left(95.0) == 5.0
