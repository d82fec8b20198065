"""The guest's initramfs: static busybox, the kernel modules the suite needs, and guest/init.

Everything else the guest runs comes from the host root over 9p, so this stays a few MB and is
rebuilt on every run (a fraction of a second) from the sources in this folder.
"""
from __future__ import annotations

import pathlib
import shutil
import subprocess
from typing import Callable

from hil_kernel import Kernel, KernelError

HERE = pathlib.Path(__file__).resolve().parent

# Modules the guest loads, in this order; modprobe --show-depends adds their dependencies first.
# Nothing autoloads them (no udev in the initramfs), so e.g. hid-generic must be listed or no
# /dev/hidraw node ever appears for a uhid device.
MODULES = [
    "virtio_pci", "9pnet_virtio", "9p",           # the host root and the results share
    "configfs",                                   # USB gadget configuration
    "can-dev", "vcan", "can-raw", "can-bcm",      # SocketCAN on virtual buses
    "hid", "uhid", "hid-generic",                 # userspace HID devices -> /dev/hidrawN
    "usbcore", "udc-core", "dummy_hcd",           # a USB host and device controller pair
    "libcomposite", "usb_f_fs", "usb_f_ss_lb",    # FunctionFS gadgets, loopback function
    "usb_f_hid", "usbhid",                        # a HID gadget and the host's USB HID driver
    "sch_tbf",                                    # a CAN queue that holds frames (full TX queue)
]
# Two virtual UDCs: one for the project's gadget, one spare (e.g. a second device).
MODULE_OPTIONS = {"dummy_hcd": "num=2"}


def resolve_modules(kern: Kernel) -> list[tuple[pathlib.Path, str]]:
    """(path of .ko inside the unpacked package, insmod options), dependencies first, no repeats."""
    order: list[tuple[pathlib.Path, str]] = []
    seen: set[pathlib.Path] = set()
    for mod in MODULES:
        r = subprocess.run(["modprobe", "-d", str(kern.root), "-S", kern.version,
                            "--show-depends", mod], capture_output=True, text=True)
        if r.returncode != 0:
            raise KernelError(f"{kern.package} has no module {mod}: {r.stderr.strip()}")
        for line in r.stdout.splitlines():
            parts = line.split()
            if not parts or parts[0] != "insmod":
                continue  # "builtin X": nothing to load
            path = pathlib.Path(parts[1])
            if path in seen:
                continue
            seen.add(path)
            name = path.name.removesuffix(".ko").replace("-", "_")
            opts = " ".join(parts[2:]) or MODULE_OPTIONS.get(name, MODULE_OPTIONS.get(mod, ""))
            order.append((path, opts))
    return order


def build_initramfs(kern: Kernel, out: pathlib.Path, log: Callable[[str], None]) -> pathlib.Path:
    stage = out.with_suffix(".stage")
    if stage.exists():
        shutil.rmtree(stage)
    for d in ("bin", "dev", "proc", "sys", "host", "lib/modules"):
        (stage / d).mkdir(parents=True)
    shutil.copy2("/bin/busybox", stage / "bin/busybox")
    shutil.copy2(HERE / "guest" / "init", stage / "init")
    (stage / "init").chmod(0o755)
    mods = resolve_modules(kern)
    with open(stage / "modules.list", "w") as f:
        for path, opts in mods:
            rel = path.relative_to(kern.root)
            dst = stage / rel
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(path, dst)
            f.write(f"/{rel} {opts}".rstrip() + "\n")
    tmp = out.with_suffix(".tmp")
    files = subprocess.run(["find", "."], cwd=stage, capture_output=True, check=True).stdout
    with open(tmp, "wb") as f:
        r = subprocess.run(["cpio", "-o", "-H", "newc", "--quiet"], cwd=stage, input=files,
                           stdout=f, stderr=subprocess.PIPE)
    if r.returncode != 0:
        raise KernelError(f"cpio failed: {r.stderr.decode().strip()}")
    tmp.rename(out)
    shutil.rmtree(stage)
    log(f"initramfs: {len(mods)} modules, {out.stat().st_size / 1e6:.1f} MB")
    return out
