"""The QEMU hardware-in-the-loop suite, once per `make test` (one guest boot runs all of it).

The CI kernel has no CAN, uhid or USB gadget support, so this is the only place the real
SocketCAN, hidraw/hidapi and libusb paths run against a kernel. It fails, never skips, when the
suite cannot run (kernel package not fetchable, QEMU missing): a green `make test` must mean the
real transports were exercised. HAPFLUID_HIL_KERNEL=rt runs it on the PREEMPT_RT kernel instead.
"""
import os
import pathlib
import subprocess
import sys

HIL = pathlib.Path(__file__).resolve().parent / "hil.py"


def test_every_guest_test_passes_on_a_real_kernel(build_dir):
    flavour = os.environ.get("HAPFLUID_HIL_KERNEL", "default")
    r = subprocess.run([sys.executable, str(HIL), "--build", str(build_dir), "--kernel", flavour],
                       capture_output=True, text=True)  # hil.py kills a hung guest itself
    print(r.stderr)
    verdict = [line for line in r.stderr.splitlines() if "PASSED" in line or "FAILED" in line]
    assert r.returncode == 0, "HIL suite failed:\n" + "\n".join(r.stderr.splitlines()[-60:])
    assert verdict and "PASSED" in verdict[-1]
