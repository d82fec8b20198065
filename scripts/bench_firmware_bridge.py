#!/usr/bin/env python3
"""Loopback round trip and device watchdog reaction, per framing (`make bench`).

For each framing it runs haptic-fake-device and haptic-device-probe (the loop's driver at 1 kHz)
as separate processes on the loopback bus and records:
  - round trip host -> device -> host: from sending a COMMAND to receiving the first STATE that
    echoes its sequence (includes waiting for the device's next 1 ms tick and the host's next
    poll: both loops run at 1 kHz, so ~1 ms is the floor, not a transport cost);
  - state rate seen by the host, bad frames, sequence gaps;
  - watchdog reaction: the host falls silent; the device's own time from the last valid command
    to zero motor torque, and the host-observed time from its silence to a state reporting it.
Both processes run under SCHED_FIFO (chrt) when the user may, as on a rig; otherwise with normal
scheduling, which the records say ("sched"): on a loaded machine those numbers include starvation.
Writes a JSON list of {"bench", "params", "metrics"} records.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile


def realtime_prefix() -> list[str]:
    try:
        ok = subprocess.run(["chrt", "-f", "60", "true"], capture_output=True).returncode == 0
    except FileNotFoundError:
        ok = False
    return ["chrt", "-f", "60"] if ok else []


PREFIX = realtime_prefix()


def run_pair(build: pathlib.Path, framing: str, seconds: float, probe_args: list[str], fake_args: list[str]):
    with tempfile.TemporaryDirectory() as tmp:
        sock = pathlib.Path(tmp) / "bus.sock"
        fake = subprocess.Popen([*PREFIX, str(build / "bin/haptic-fake-device"), "--address", str(sock), "--framing", framing,
                                 "--duration", str(seconds + 1.0), *fake_args],
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        if "ready" not in fake.stdout.readline():
            fake.kill()
            sys.exit("haptic-fake-device did not start")
        probe = subprocess.run([*PREFIX, str(build / "bin/haptic-device-probe"), "--transport", "loopback", "--address",
                                str(sock), "--framing", framing, "--duration", str(seconds), *probe_args],
                               capture_output=True, text=True, timeout=seconds + 30)
        if probe.returncode != 0:
            fake.kill()
            sys.exit(f"haptic-device-probe failed: {probe.stderr}")
        out, _ = fake.communicate(timeout=seconds + 30)
        return json.loads(probe.stdout), json.loads(out.strip().splitlines()[-1])


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--build", type=pathlib.Path, default=pathlib.Path("build"))
    p.add_argument("--out", type=pathlib.Path, required=True)
    p.add_argument("--seconds", type=float, default=5.0, help="round-trip run per framing")
    args = p.parse_args()
    records = []
    for framing in ("can", "canfd", "hid", "bulk"):
        print(f"bench_firmware_bridge: round trip, {framing}, {args.seconds} s", file=sys.stderr)
        report, _ = run_pair(args.build, framing, args.seconds, ["--force", "1,0,0", "--enable"], [])
        records.append({"bench": "firmware_bridge_loopback_round_trip",
                        "params": {"framing": framing, "seconds": args.seconds, "rate_hz": 1000,
                                   "sched": "fifo" if PREFIX else "other"},
                        "metrics": {"rtt_p50_us": report["rtt_p50_us"], "rtt_p99_us": report["rtt_p99_us"],
                                    "rtt_max_us": report["rtt_max_us"], "rtt_samples": report["rtt_samples"],
                                    "state_rate_hz": report["state_rate_hz"], "frames_bad": report["frames_bad"],
                                    "sequence_gaps": report["sequence_gaps"]}})
        print(f"  p50 {report['rtt_p50_us']:.0f} us, p99 {report['rtt_p99_us']:.0f} us, "
              f"state {report['state_rate_hz']:.1f} Hz", file=sys.stderr)
    reactions, seen = [], []
    for trial in range(5):
        print(f"bench_firmware_bridge: watchdog trial {trial + 1}/5", file=sys.stderr)
        report, summary = run_pair(args.build, "can", 0.8, ["--force", "1,0,0", "--enable", "--silent-after", "0.5"],
                                   ["--watchdog-ms", "20"])
        reactions.append(summary["watchdog_reaction_ms"])
        seen.append(report["watchdog_seen_after_silence_ms"])
    records.append({"bench": "firmware_bridge_device_watchdog",
                    "params": {"watchdog_ms": 20, "framing": "can", "trials": len(reactions),
                               "sched": "fifo" if PREFIX else "other"},
                    "metrics": {"device_reaction_ms_max": max(reactions), "device_reaction_ms_mean": sum(reactions) / len(reactions),
                                "host_observed_ms_max": max(seen), "host_observed_ms_mean": sum(seen) / len(seen)}})
    print(f"  device reaction {min(reactions):.2f}..{max(reactions):.2f} ms, host sees it after "
          f"{min(seen):.2f}..{max(seen):.2f} ms", file=sys.stderr)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(records, indent=1) + "\n")


if __name__ == "__main__":
    main()
