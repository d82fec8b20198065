#!/usr/bin/env python3
"""Hardware-in-the-loop suite on a real kernel: host-side driver.

The development and CI kernels have no CAN, uhid or USB gadget support, so this boots Debian's
own kernel under QEMU (TCG, no KVM needed) with a tiny busybox initramfs, shares the host root
read-only into the guest over 9p, and runs the guest tests in `tests/hil-kernel/guest/` against
the binaries built on the host, unchanged. One boot runs the whole suite; the guest writes JUnit
XML and a summary line into a writable results share and powers off.

    python3 tests/hil-kernel/hil.py --build build [--kernel default|rt] [--only REGEX]

Exit status: 0 when every planned guest test passed; 1 when any failed, was missing or the guest
hung; 2 when the suite could not run at all (kernel package not fetchable, QEMU missing). There
is no "skipped": a suite that cannot run fails, loudly.
"""
from __future__ import annotations

import argparse
import os
import pathlib
import re
import selectors
import shutil
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from hil_kernel import KernelError, fetch_kernel  # noqa: E402
from hil_initramfs import build_initramfs  # noqa: E402
from hil_results import read_results  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
SOURCE_DIR = HERE.parent.parent
GUEST_DIR = HERE / "guest"
QBOOT = pathlib.Path("/usr/share/qemu/qboot.rom")

# Per-test time limit inside the guest when a test does not declare `# hil-timeout: N` (seconds).
DEFAULT_TEST_TIMEOUT_S = 60
# The host watches the guest's progress, not the clock: a guest is hung when it has not reached
# its first test within BOOT_LIMIT_S, when a test runs past its own limit plus TEST_GRACE_S (the
# guest enforces each test's limit itself, so only a stuck kernel or init gets there), or when
# nothing follows a test's result within BETWEEN_LIMIT_S (the next test or the power-off). On a
# 2-core host beside a CPU hog the suite's wall time varies from 5 to 10 min, so no fixed total
# fits it; `--timeout` still sets one when asked.
BOOT_LIMIT_S = 240
TEST_GRACE_S = 60
BETWEEN_LIMIT_S = 120
RUNNING = re.compile(r"^HIL-TEST \[\d+/\d+\] (\S+): running \(limit (\d+) s\)")
FINISHED = re.compile(r"^HIL-TEST \[\d+/\d+\] (\S+): (?!running)")


class ProgressWatchdog:
    """When the guest counts as hung, from the console lines it prints (monotonic seconds)."""

    def __init__(self, start: float, total_limit_s: float | None = None):
        self.total_deadline = start + total_limit_s if total_limit_s else None
        self.deadline = start + BOOT_LIMIT_S
        self.waiting_for = "the first test to start"

    def line(self, now: float, line: str) -> None:
        m = RUNNING.match(line)
        if m:
            self.deadline = now + int(m.group(2)) + TEST_GRACE_S
            self.waiting_for = f"{m.group(1)} to finish (its limit is {m.group(2)} s)"
            return
        m = FINISHED.match(line)
        if m:
            self.deadline = now + BETWEEN_LIMIT_S
            self.waiting_for = f"the next test or the power-off after {m.group(1)}"

    def expired(self, now: float) -> str | None:
        """Why the guest counts as hung at `now`, or None."""
        if self.total_deadline is not None and now >= self.total_deadline:
            return "the --timeout limit passed"
        if now >= self.deadline:
            return f"no progress: still waiting for {self.waiting_for}"
        return None

    def seconds_left(self, now: float) -> float:
        ends = [self.deadline] + ([self.total_deadline] if self.total_deadline is not None else [])
        return min(ends) - now


def log(msg: str) -> None:
    print(f"hil: {msg}", file=sys.stderr, flush=True)


def plan_tests(only: str | None) -> list[tuple[str, int, pathlib.Path]]:
    """The guest tests: every guest/t_*.sh, in name order, with its declared time limit."""
    tests = []
    for path in sorted(GUEST_DIR.glob("t_*.sh")):
        name = path.stem[2:]
        if only and not re.search(only, name):
            continue
        timeout = DEFAULT_TEST_TIMEOUT_S
        m = re.search(r"^# hil-timeout:\s*(\d+)", path.read_text(), re.M)
        if m:
            timeout = int(m.group(1))
        tests.append((name, timeout, path))
    return tests


def ensure_host_tools() -> None:
    """QEMU, busybox, cpio and kmod come from `scripts/install-deps.sh hil`; run it if missing."""
    need = {"qemu-system-x86_64": "qemu-system-x86", "cpio": "cpio", "depmod": "kmod"}
    missing = [pkg for tool, pkg in need.items() if shutil.which(tool) is None
               and not pathlib.Path("/usr/sbin", tool).exists()]
    if not pathlib.Path("/bin/busybox").exists():
        missing.append("busybox-static")
    if not QBOOT.exists():
        missing.append("qemu-system-x86 (qboot.rom)")
    if missing or not pathlib.Path("/usr/bin/udevadm").exists():
        log(f"installing the HIL host packages ({', '.join(missing) or 'udev'})")
        subprocess.run(["bash", str(SOURCE_DIR / "scripts/install-deps.sh"), "hil"], check=False)
    still = [t for t in need if shutil.which(t) is None and not pathlib.Path("/usr/sbin", t).exists()]
    if still or not QBOOT.exists() or not pathlib.Path("/bin/busybox").exists():
        raise KernelError("the HIL suite needs qemu-system-x86, busybox-static, cpio and kmod: "
                          "run `sudo bash scripts/install-deps.sh hil`")


def write_plan(results: pathlib.Path, tests, build: pathlib.Path, flavour: str) -> None:
    results.mkdir(parents=True, exist_ok=True)
    with open(results / "plan.tsv", "w") as f:
        for name, timeout, path in tests:
            f.write(f"{name}\t{timeout}\t{path}\n")
    with open(results / "plan.env", "w") as f:
        f.write(f"HIL_SRC={SOURCE_DIR}\nHIL_BUILD={build}\nHIL_FLAVOUR={flavour}\n")


def checkout_shares(build: pathlib.Path) -> list[str]:
    """The checkout (and a build folder outside it) as 9p shares of their own: the guest mounts
    fresh tmpfs on /tmp, /run, /var/tmp and /dev/shm, which would hide a clone that lives there
    (guest/init mounts these shares over the host root's view of the same paths)."""
    shares = ["-virtfs", f"local,path={SOURCE_DIR},mount_tag=hilsrc,security_model=none,readonly=on,multidevs=remap"]
    if SOURCE_DIR not in build.resolve().parents:
        shares += ["-virtfs", f"local,path={build.resolve()},mount_tag=hilbuild,security_model=none,readonly=on,"
                   "multidevs=remap"]
    return shares


def boot(kernel: pathlib.Path, initrd: pathlib.Path, results: pathlib.Path, build: pathlib.Path,
         total_limit_s: float | None, verbose: bool) -> tuple[int | None, list[str]]:
    """Boots the guest, streams its console as progress, kills it once its progress stops.

    Returns (qemu exit status or None when it had to be killed, console lines)."""
    cmd = [
        "qemu-system-x86_64", "-accel", "tcg", "-cpu", "max", "-smp", "1", "-m", "1024",
        "-nographic", "-no-reboot", "-net", "none", "-bios", str(QBOOT),
        "-kernel", str(kernel), "-initrd", str(initrd),
        "-append", "console=ttyS0 quiet panic=-1 loglevel=3",
        "-virtfs", "local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap",
        "-virtfs", f"local,path={results},mount_tag=results,security_model=none",
        *checkout_shares(build),
    ]
    console_path = results / "console.log"
    lines: list[str] = []
    start = time.monotonic()
    watchdog = ProgressWatchdog(start, total_limit_s)
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT)
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    buf = b""
    killed = False
    with open(console_path, "wb") as console:
        while True:
            now = time.monotonic()
            why = watchdog.expired(now)
            if why:
                log(f"guest hung after {now - start:.0f} s ({why}): killing QEMU (pid {proc.pid})")
                proc.kill()
                killed = True
                break
            left = watchdog.seconds_left(now)
            if not sel.select(timeout=min(left, 1.0)):
                if proc.poll() is not None:
                    break
                continue
            chunk = os.read(proc.stdout.fileno(), 65536)
            if not chunk:
                break
            console.write(chunk)
            buf += chunk
            while b"\n" in buf:
                raw, buf = buf.split(b"\n", 1)
                line = raw.decode("utf-8", "replace").rstrip("\r")
                lines.append(line)
                now = time.monotonic()
                watchdog.line(now, line)
                t = now - start
                if verbose or line.startswith("HIL"):
                    print(f"  [{t:6.1f} s] {line}", file=sys.stderr, flush=True)
    if buf:
        lines.append(buf.decode("utf-8", "replace"))
    proc.wait()
    return (None if killed else proc.returncode), lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build", help="CMake build folder (binaries in BUILD/bin)")
    ap.add_argument("--kernel", default="default", choices=["default", "rt"],
                    help="Debian kernel flavour: default (linux-image-amd64) or rt (PREEMPT_RT)")
    ap.add_argument("--only", help="run only guest tests whose name matches this regex")
    ap.add_argument("--timeout", type=float,
                    help="hard wall-clock limit for the whole guest, seconds (default: none; the guest "
                         "is killed only when its progress stops)")
    ap.add_argument("--verbose", action="store_true", help="echo the whole guest console")
    args = ap.parse_args()

    wall0 = time.monotonic()
    build = (SOURCE_DIR / args.build).resolve() if not os.path.isabs(args.build) \
        else pathlib.Path(args.build)
    cache = build / "hil"
    tests = plan_tests(args.only)
    if not tests:
        log("no guest test matches")
        return 2
    try:
        ensure_host_tools()
        kern = fetch_kernel(args.kernel, cache / "kernel", log)
        initrd = build_initramfs(kern, cache / f"initrd-{kern.version}.cpio", log)
    except KernelError as e:
        log(f"FAILED: cannot run the hardware-in-the-loop suite: {e}")
        return 2

    results = cache / f"results-{args.kernel}"
    if results.exists():
        shutil.rmtree(results)
    write_plan(results, tests, build, args.kernel)
    worst = BOOT_LIMIT_S + sum(limit + TEST_GRACE_S for _, limit, _ in tests) + BETWEEN_LIMIT_S
    log(f"booting {kern.package} ({kern.version}) under QEMU/TCG: {len(tests)} guest tests, "
        + (f"hard limit {args.timeout:.0f} s" if args.timeout else f"hung-guest watchdog (at most {worst} s)"))
    status, lines = boot(kern.vmlinux, initrd, results, build, args.timeout, args.verbose)

    report = read_results(results, [name for name, _, _ in tests])
    wall = time.monotonic() - wall0
    for name, outcome in report.outcomes.items():
        if outcome.status != "pass":
            log(f"--- {name}: {outcome.status.upper()} ({outcome.message}); log tail:")
            for line in outcome.log_tail:
                print(f"    {line}", file=sys.stderr)
    if status is None or report.summary is None:
        log("the guest console ended with:")
        for line in lines[-25:]:
            print(f"    {line}", file=sys.stderr)
    ok = status is not None and report.summary is not None and report.all_passed
    log(f"{'PASSED' if ok else 'FAILED'}: {report.passed}/{len(tests)} guest tests passed on "
        f"{kern.package}; wall time {wall:.1f} s (results: {results})")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
