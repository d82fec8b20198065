"""Checks what hapfluid.can_monitor decoded live from vcan0 (one JSON object per line) against
what the host commanded through haptic-device-probe (its JSON report), in one python process.

  check_can_monitor.py MONITOR.jsonl PROBE.json NODE FX FY FZ
"""
import json
import sys


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def main():
    monitor, probe_path, node = sys.argv[1], sys.argv[2], int(sys.argv[3])
    force = [float(v) for v in sys.argv[4:7]]
    items = [json.loads(line) for line in open(monitor) if line.strip().startswith("{")]
    stats = [i["stats"] for i in items if "stats" in i]
    msgs = [i for i in items if "stats" not in i]
    bad = [i for i in msgs if "bad" in i]
    if bad:
        fail(f"can_monitor flagged {len(bad)} frames of a clean bus as bad, first: {bad[0]}")
    if not stats:
        fail("can_monitor printed no statistics")
    by_type = {}
    for m in msgs:
        if m.get("node") == node and "type" in m:
            by_type.setdefault(m["type"], []).append(m)
    print("decoded per type:", {k: len(v) for k, v in by_type.items()}, "stats:", stats[-1])
    states = by_type.get("STATE", [])
    if len(states) < 10:
        fail(f"only {len(states)} STATE messages of node {node} decoded live")
    commands = by_type.get("COMMAND", [])
    # The command the host sent, back from the wire through the Python codec (0.001 N steps).
    matching = [c for c in commands if all(abs(a - b) < 1.5e-3 for a, b in zip(c["fields"]["force_n"], force))
                and c["fields"]["flags"] & 1]
    if not matching:
        fail(f"no enabled COMMAND with force {force} N among {len(commands)} decoded commands")
    if not any(s["fields"]["status"] & 1 for s in states):
        fail("no decoded STATE shows the motors enabled (status bit 0) although the host enabled them")
    probe = json.load(open(probe_path))
    print("haptic-device-probe:", {k: probe[k] for k in ("states", "frames_ok", "frames_bad", "commands_sent",
                                                       "send_errors", "faults_seen", "status_seen", "info")})
    if probe["frames_bad"] or probe["send_errors"]:
        fail(f"haptic-device-probe saw bad frames or send errors: {probe}")
    if probe["states"] < 100 or probe["commands_sent"] < 100:
        fail(f"haptic-device-probe exchanged too little: {probe['states']} states, {probe['commands_sent']} commands")
    if not probe["status_seen"] & 1:
        fail("haptic-device-probe never saw the motors enabled")
    if probe["info"] is None or probe["info"]["vendor_id"] != 0x1209:
        fail(f"the INFO handshake failed: {probe['info']}")
    print(f"PASS: can_monitor decoded {len(states)} STATE and {len(commands)} COMMAND (force {force} N) live")


if __name__ == "__main__":
    main()
