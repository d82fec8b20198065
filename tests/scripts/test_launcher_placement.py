"""Where scripts/hapfluid.py puts the processes of a live run: as on a rig (scripts/systemd), the
loop's CPU holds the loop alone among the host's services; the fake devices, which stand in for
hardware outside the host, go beside it so their 1 kHz FIFO ticks do not preempt the sim."""


def placement(script, monkeypatch, cpus, loop_cpu, source_dir):
    monkeypatch.syspath_prepend(str(source_dir / "scripts"))  # the launcher imports its neighbours
    launcher = script("hapfluid")
    monkeypatch.setattr(launcher.os, "sched_getaffinity", lambda pid: set(cpus))
    return launcher.cpu_placement({"cpu": loop_cpu})


def test_services_stay_off_the_loops_cpu_and_devices_go_beside_it(script, monkeypatch, source_dir):
    devices, services = placement(script, monkeypatch, {0, 1}, 1, source_dir)
    assert devices == {1} and services == {0}
    devices, services = placement(script, monkeypatch, {0, 1, 2, 3}, 3, source_dir)
    assert devices == {3} and services == {0, 1, 2}


def test_nothing_is_pinned_without_a_pinned_loop_or_a_second_cpu(script, monkeypatch, source_dir):
    assert placement(script, monkeypatch, {0, 1}, -1, source_dir) == (set(), set())
    assert placement(script, monkeypatch, {0}, 0, source_dir) == (set(), set())
    # A loop pinned to a CPU this process may not use (a rig file for another machine).
    assert placement(script, monkeypatch, {0, 1}, 5, source_dir) == (set(), set())
