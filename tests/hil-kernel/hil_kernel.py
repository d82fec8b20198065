"""Debian's kernel for the HIL guest: resolve, download with apt, unpack, index modules.

The package is whatever Debian 12's metapackage currently depends on (`linux-image-amd64`, or
`linux-image-rt-amd64` for PREEMPT_RT), fetched with `apt-get download` and cached under the build
folder, so the suite follows Debian's security updates without an edit here. Nothing here passes
quietly: a kernel that cannot be resolved or fetched raises KernelError with the reason.
"""
from __future__ import annotations

import dataclasses
import lzma
import os
import pathlib
import re
import shutil
import subprocess
from typing import Callable

METAPACKAGES = {"default": "linux-image-amd64", "rt": "linux-image-rt-amd64"}
XZ_MAGIC = b"\xfd7zXZ\x00"


class KernelError(RuntimeError):
    pass


@dataclasses.dataclass
class Kernel:
    package: str          # e.g. linux-image-6.1.0-56-amd64
    version: str          # module directory name, e.g. 6.1.0-56-amd64
    root: pathlib.Path    # the unpacked package (boot/, lib/modules/VERSION/)
    vmlinux: pathlib.Path  # the image QEMU boots


def _run(cmd: list[str], cwd: pathlib.Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)


def resolve_package(flavour: str, log: Callable[[str], None]) -> str:
    """The concrete kernel package the flavour's metapackage depends on right now."""
    meta = METAPACKAGES[flavour]
    for attempt in range(2):
        r = _run(["apt-cache", "depends", "--no-recommends", "--no-suggests", meta])
        m = re.search(r"Depends:\s*(linux-image-\S+)", r.stdout)
        if r.returncode == 0 and m:
            return m.group(1)
        if attempt == 0 and os.geteuid() == 0:
            # An empty or stale package list says "no packages found": refresh once.
            log("apt has no record of the kernel metapackage: running apt-get update")
            _run(["apt-get", "update", "-q"])
    raise KernelError(f"apt-cache cannot resolve {meta} (Debian 12 apt sources needed): "
                      f"{(r.stderr or r.stdout).strip()[:300]}")


def _extract_vmlinux(vmlinuz: pathlib.Path, out: pathlib.Path) -> pathlib.Path:
    """The decompressed ELF inside the bzImage: QEMU loads it through its PVH note, skipping the
    in-guest xz decompression that costs seconds under TCG."""
    data = vmlinuz.read_bytes()
    at = data.find(XZ_MAGIC)
    if at < 0:
        return vmlinuz  # not xz: boot the bzImage as is (slower, still correct)
    dec = lzma.LZMADecompressor(format=lzma.FORMAT_XZ)
    elf = dec.decompress(data[at:])
    if not elf.startswith(b"\x7fELF"):
        return vmlinuz
    tmp = out.with_suffix(".tmp")
    tmp.write_bytes(elf)
    tmp.rename(out)
    return out


def fetch_kernel(flavour: str, cache: pathlib.Path, log: Callable[[str], None]) -> Kernel:
    cache.mkdir(parents=True, exist_ok=True)
    try:
        package = resolve_package(flavour, log)
    except KernelError:
        # Offline with a kernel already cached for this flavour: use it, and say so.
        cached = sorted(cache.glob(f"*/.complete-{flavour}"))
        if not cached:
            raise
        package = cached[-1].parent.name
        log(f"apt cannot resolve {METAPACKAGES[flavour]}: using the cached {package}")
    root = cache / package
    version = package.removeprefix("linux-image-")
    done = root / f".complete-{flavour}"
    if not done.exists():
        if root.exists():
            shutil.rmtree(root)
        dl = cache / "download"
        if dl.exists():
            shutil.rmtree(dl)
        dl.mkdir()
        log(f"downloading {package} with apt-get download")
        r = _run(["apt-get", "download", "-q", package], cwd=dl)
        debs = list(dl.glob("*.deb"))
        if r.returncode != 0 or len(debs) != 1:
            raise KernelError(f"`apt-get download {package}` failed: "
                              f"{(r.stderr or r.stdout).strip()[-400:]}")
        tmp = cache / (package + ".unpack")
        if tmp.exists():
            shutil.rmtree(tmp)
        r = _run(["dpkg-deb", "-x", str(debs[0]), str(tmp)])
        if r.returncode != 0:
            raise KernelError(f"dpkg-deb -x {debs[0].name} failed: {r.stderr.strip()}")
        shutil.rmtree(dl)
        sysmap = tmp / "boot" / f"System.map-{version}"
        if not (tmp / "lib/modules" / version).is_dir() or not sysmap.exists():
            raise KernelError(f"{package} has no lib/modules/{version} or System.map")
        # The package ships no modules.dep (the postinst makes it): build it for modprobe -d.
        r = _run(["depmod", "-b", str(tmp), "-F", str(sysmap), version])
        if r.returncode != 0:
            raise KernelError(f"depmod failed for {package}: {r.stderr.strip()}")
        _extract_vmlinux(tmp / "boot" / f"vmlinuz-{version}", tmp / "vmlinux")
        tmp.rename(root)
        done.touch()
    else:
        log(f"kernel {package} (cached in {root})")
    vmlinux = root / "vmlinux"
    if not vmlinux.exists():
        vmlinux = root / "boot" / f"vmlinuz-{version}"
    return Kernel(package=package, version=version, root=root, vmlinux=vmlinux)
