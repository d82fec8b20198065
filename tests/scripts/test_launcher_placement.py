"""Where the launcher (hapfluid.launcher) puts the processes of a live run: as on a rig
(scripts/systemd), the loop's CPU holds the loop alone among the host's services; the fake devices,
which stand in for hardware outside the host, go beside it so their 1 kHz FIFO ticks do not
preempt the sim."""
from hapfluid import launcher


def placement(monkeypatch, cpus, loop_cpu):
    monkeypatch.setattr(launcher.os, "sched_getaffinity", lambda pid: set(cpus))
    return launcher.cpu_placement({"cpu": loop_cpu})


def test_services_stay_off_the_loops_cpu_and_devices_go_beside_it(monkeypatch):
    devices, services = placement(monkeypatch, {0, 1}, 1)
    assert devices == {1} and services == {0}
    devices, services = placement(monkeypatch, {0, 1, 2, 3}, 3)
    assert devices == {3} and services == {0, 1, 2}


def test_nothing_is_pinned_without_a_pinned_loop_or_a_second_cpu(monkeypatch):
    assert placement(monkeypatch, {0, 1}, -1) == (set(), set())
    assert placement(monkeypatch, {0}, 0) == (set(), set())
    # A loop pinned to a CPU this process may not use (a rig file for another machine).
    assert placement(monkeypatch, {0, 1}, 5) == (set(), set())
