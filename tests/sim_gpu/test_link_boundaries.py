"""The process boundaries of docs/architecture.md in the link: the simulator and the renderer
touch no device. Neither links the loop (hapfluid_rt), the device drivers (hapfluid_device,
libusb, hidapi) or the wire codec; haptic-sim speaks systemd's notify protocol through its own
small library."""
import re

import pytest

DEVICE_SIDE = ("libhapfluid_rt.a", "libhapfluid_device.a", "libhapfluid_wire.a", "libhapfluid_fake_firmware.a",
               "libusb", "hidapi")


def link_inputs(build_dir, executable):
    """The inputs of the executable's link step in the Ninja build file."""
    ninja = (build_dir / "build.ninja").read_text()
    m = re.search(rf"^build bin/{re.escape(executable)}: \S+ (.*?)(?<!\$)\n((?:  .*\n)*)", ninja, re.M)
    if not m:
        pytest.fail(f"no link step for bin/{executable} in {build_dir / 'build.ninja'}")
    return m.group(0)


@pytest.mark.parametrize("executable", ["haptic-sim", "haptic-render"])
def test_the_sim_and_the_renderer_link_nothing_of_the_devices(build_dir, executable):
    step = link_inputs(build_dir, executable)
    assert "libhapfluid_shm.a" in step  # the parse found the real step
    assert [lib for lib in DEVICE_SIDE if lib in step] == []


def test_haptic_sim_speaks_sd_notify_through_libsystemd(build_dir):
    step = link_inputs(build_dir, "haptic-sim")
    assert "libhapfluid_sd_notify.a" in step and "libsystemd" in step
