"""Checks the hapfluid Debian package the way a rig administrator meets it, in a fresh Debian 12
root (mmdebstrap, the apt variant): `apt install ./hapfluid_*.deb` pulls in its dependencies and
creates the hapfluid user, leaving every service disabled; `systemd-analyze verify` accepts its
units; every tool answers; the launcher runs the default scene on the fake rig with the installed
binaries; `apt remove` (after the administrator enabled the stack) leaves no unit, link or rule
behind, and purge removes the site settings.

  scripts/check_deb.py --deb out/deb/hapfluid_0.1.0_amd64.deb --out out/deb

Needs root (chroot, bind mounts) and the network to Debian's archive. Each step prints as it
starts; check.json in --out records each step's result and duration, logs/ their output.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

UNITS = ["hapfluid.target", "haptic-rt.service", "haptic-sim.service", "haptic-render.service",
         "haptic-trace.service", "haptic-dashboard.service"]
TOOLS = ["haptic-rt", "haptic-sim", "haptic-render", "haptic-trace", "haptic-status", "haptic-config",
         "haptic-fake-device", "haptic-device-probe"]
PYTHON_COMMANDS = ["hapfluid", "hapfluid-can-monitor", "hapfluid-latency-report", "hapfluid-motion-to-force",
                   "hapfluid-plot-wrenches", "haptic-dashboard"]
# Where a removed package could leave a unit, an enablement link, a rule or a command behind.
LEFTOVER_DIRS = ["etc/systemd/system", "usr/lib/systemd/system", "usr/lib/udev/rules.d", "usr/lib/sysusers.d",
                 "usr/bin"]
MOUNTS = ["proc", "sys", "dev", "dev/shm"]


class Failed(Exception):
    pass


class Root:
    """A Debian root with the host's /proc, /sys, /dev and /dev/shm bound in (the stack's
    segments live in /dev/shm; the loop takes SCHED_FIFO as root here as on the host)."""

    def __init__(self, path: pathlib.Path, logs: pathlib.Path):
        self.path, self.logs, self.mounted = path, logs, []

    def mount(self):
        for m in MOUNTS:
            target = self.path / m
            target.mkdir(parents=True, exist_ok=True)
            subprocess.run(["mount", "--bind", f"/{m}", str(target)], check=True)
            self.mounted.append(target)

    def unmount(self):
        for target in reversed(self.mounted):
            subprocess.run(["umount", "--lazy", str(target)], check=False)
        self.mounted.clear()

    def still_mounted(self) -> list[str]:
        inside = str(self.path) + "/"
        return [line.split()[1] for line in pathlib.Path("/proc/self/mounts").read_text().splitlines()
                if line.split()[1].startswith(inside)]

    def run(self, name: str, command: str, check: bool = True) -> subprocess.CompletedProcess:
        """Runs `command` with sh in the root; its output goes to logs/<name>.log."""
        env = {"PATH": "/usr/sbin:/usr/bin:/sbin:/bin", "DEBIAN_FRONTEND": "noninteractive", "LANG": "C.UTF-8",
               "HOME": "/root"}
        r = subprocess.run(["chroot", str(self.path), "sh", "-c", command], env=env, capture_output=True, text=True)
        (self.logs / f"{name}.log").write_text(f"$ {command}\n--- stdout\n{r.stdout}--- stderr\n{r.stderr}"
                                               f"--- exit {r.returncode}\n")
        if check and r.returncode != 0:
            tail = "\n".join((r.stdout + r.stderr).strip().splitlines()[-12:])
            raise Failed(f"`{command}` exited {r.returncode} (logs/{name}.log):\n{tail}")
        return r


def leftovers(root: pathlib.Path) -> list[str]:
    found = []
    for d in LEFTOVER_DIRS:
        base = root / d
        if base.is_dir():
            found += [str(p.relative_to(root)) for p in base.rglob("*") if "hapfluid" in p.name or "haptic" in p.name]
    return sorted(found)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_page(port: int, server: subprocess.Popen, timeout_s: float = 30) -> dict:
    """The page's first snapshot from haptic-status, once the server answers with one."""
    give_up = time.monotonic() + timeout_s
    while time.monotonic() < give_up and server.poll() is None:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/status", timeout=2) as r:
                snapshot = json.load(r)["snapshot"]
            if snapshot.get("observer") == "live":
                return snapshot
        except (OSError, ValueError):
            pass
        time.sleep(0.2)
    raise Failed(f"haptic-dashboard never served a snapshot (exit {server.poll()}, logs/dashboard.log)")


def check(root: Root, deb: pathlib.Path, results: dict, step):
    p = root.path
    with step("install"):
        shutil.copy(deb, p / "tmp" / deb.name)
        r = root.run("install", f"apt-get install -y -q /tmp/{deb.name}")
        results["packages_pulled_in"] = sum(1 for line in r.stdout.splitlines() if line.startswith("Unpacking "))
    with step("user, group, services disabled"):
        root.run("user", "getent passwd hapfluid && getent group hapfluid && id hapfluid-dashboard | grep -q '(hapfluid)'")
        states = root.run("enabled", "systemctl is-enabled " + " ".join(UNITS), check=False).stdout.split()
        if states != ["disabled"] * len(UNITS):
            raise Failed(f"after install the units are {dict(zip(UNITS, states))}, not all disabled")
    with step("systemd-analyze verify"):
        r = root.run("verify", "systemd-analyze verify " + " ".join(f"/usr/lib/systemd/system/{u}" for u in UNITS),
                     check=False)
        if r.returncode != 0 or r.stderr.strip():
            raise Failed(f"systemd-analyze verify (exit {r.returncode}):\n{r.stderr.strip()}")
    with step("every tool answers"):
        versions = {t: root.run(f"version-{t}", f"{t} --version").stdout.split()[-1] for t in TOOLS}  # "tool <id>"
        if len(set(versions.values())) != 1:
            raise Failed(f"the tools report different builds: {versions}")
        results["build_id"] = next(iter(versions.values()))
        for c in PYTHON_COMMANDS:
            root.run(f"help-{c}", f"{c} --help")
        # python-can finds the package's bus through its entry point, in the system's python3.
        root.run("can-interface", "python3 -c \"import can.interfaces as i; "
                                  "assert 'hapfluid_loopback' in i.BACKENDS, sorted(i.BACKENDS)\"")
    with step("the default scene on the fake rig, live"):
        root.run("run", "cd /tmp && hapfluid run --duration 10 --no-cyclictest --out /tmp/hapfluid-run")
        summary = json.loads((p / "tmp/hapfluid-run/summary.json").read_text())
        results["run_summary"] = summary
        if not summary.get("ok") or summary.get("build_id") != results["build_id"]:
            raise Failed(f"the run's summary says ok={summary.get('ok')}, build {summary.get('build_id')}")
        if not max(summary.get("max_force_on_hand_n", {}).values(), default=0) > 0:
            raise Failed("the hand felt no force from the fluid in the installed stack's run")
        shutil.copytree(p / "tmp/hapfluid-run", root.logs.parent / "run", dirs_exist_ok=True)
    with step("the operator's page serves, as its own user"):
        # As its unit runs it: its own user, trusting the services' user's segments, here with
        # nothing to watch: the page must answer and say it waits for the loop and the sim.
        port = free_port()
        server = subprocess.Popen([shutil.which("chroot") or "/usr/sbin/chroot", "--userspec=hapfluid-dashboard:hapfluid", str(p), "haptic-dashboard",
                                   "--listen", f"127.0.0.1:{port}", "--trust-user", "hapfluid",
                                   "--shm-prefix", "hapfluid-check-deb"],
                                  stdout=subprocess.DEVNULL, stderr=open(root.logs / "dashboard.log", "w"),
                                  env={"PATH": "/usr/bin:/bin", "HOME": "/"})
        try:
            snapshot = wait_for_page(port, server)
        finally:
            server.terminate()
            code = server.wait(timeout=15)
        if snapshot.get("loop", {}).get("status") != "waiting" or code != 0:
            raise Failed(f"the page said {snapshot} and the server exited {code} (logs/dashboard.log)")
    with step("remove after the stack was enabled"):
        root.run("enable", "systemctl enable hapfluid.target " + " ".join(u for u in UNITS if u.endswith(".service")))
        root.run("remove", "apt-get remove -y -q hapfluid")
        left = leftovers(p)
        if left:
            raise Failed(f"apt remove left behind: {left}")
        if not (p / "etc/hapfluid/hapfluid.env").exists():
            raise Failed("apt remove took the site settings (/etc/hapfluid/hapfluid.env), a conffile purge removes")
    with step("purge"):
        root.run("purge", "apt-get purge -y -q hapfluid")
        if (p / "etc/hapfluid").exists():
            raise Failed(f"apt purge left /etc/hapfluid: {sorted(x.name for x in (p / 'etc/hapfluid').iterdir())}")
        if root.run("dpkg-status", "dpkg -s hapfluid", check=False).returncode == 0:
            raise Failed("dpkg still knows hapfluid after purge")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--deb", type=pathlib.Path, required=True, help="the package to check")
    ap.add_argument("--out", type=pathlib.Path, required=True, help="folder for check.json and logs/")
    ap.add_argument("--suite", default="bookworm", help="Debian release of the fresh root (default: bookworm)")
    args = ap.parse_args(argv)
    if not args.deb.is_file():
        ap.error(f"--deb {args.deb}: no such file")
    if not shutil.which("mmdebstrap"):
        ap.error("mmdebstrap is missing (scripts/install-deps.sh deb)")
    logs = args.out / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    results = {"deb": str(args.deb.resolve()), "suite": args.suite, "steps": []}
    t_all = time.monotonic()

    class step:
        def __init__(self, name):
            self.name = name

        def __enter__(self):
            print(f"check-deb: {self.name} ...", flush=True)
            self.t0 = time.monotonic()

        def __exit__(self, kind, value, tb):
            seconds = round(time.monotonic() - self.t0, 1)
            results["steps"].append({"step": self.name, "ok": kind is None, "seconds": seconds})
            print(f"check-deb: {self.name}: {'ok' if kind is None else 'FAILED'} ({seconds} s)", flush=True)

    failure = None
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="hapfluid-deb-root-"))
    root = Root(tmp / "root", logs)
    try:
        try:
            with step(f"fresh Debian root ({args.suite})"):
                r = subprocess.run(["mmdebstrap", "--variant=apt", "--quiet", "--skip=cleanup/apt/lists",
                                    args.suite, str(root.path)], capture_output=True, text=True)
                (logs / "mmdebstrap.log").write_text(r.stdout + r.stderr)
                if r.returncode != 0:
                    raise Failed(f"mmdebstrap exited {r.returncode} (logs/mmdebstrap.log)")
            root.mount()
            check(root, args.deb, results, step)
        except Failed as e:
            failure = str(e)
        except Exception as e:  # a defect of this script: said, and the root still cleaned up
            failure = f"{type(e).__name__}: {e}"
    finally:
        root.unmount()
        # Never delete through a mount that is still there: that would be the host's /dev.
        mounted = root.still_mounted()
        if mounted:
            print(f"check-deb: left {tmp} in place, still mounted: {mounted}", file=sys.stderr)
        else:
            shutil.rmtree(tmp, ignore_errors=True)
    results["ok"] = failure is None
    results["seconds"] = round(time.monotonic() - t_all, 1)
    if failure:
        results["failure"] = failure
    (args.out / "check.json").write_text(json.dumps(results, indent=2) + "\n")
    if failure:
        print(f"check-deb: FAILED: {failure}", file=sys.stderr)
        return 1
    print(f"check-deb: {args.deb.name} installs, verifies, runs and removes cleanly ({results['seconds']} s); "
          f"{args.out / 'check.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
