"""Decode hapfluid device traffic: live (python-can: socketcan on a rig, the loopback bus in tests
and without CAN hardware) or from a recorded log (candump .log, .asc, .blf, anything python-can
reads). Every frame is checked by the protocol codec (CRC, ranges, frame sets) and, with --dbc
signals, shown through the project's DBC with cantools, exactly as candump + cantools would.

  hapfluid-can-monitor --interface socketcan --channel can0
  hapfluid-can-monitor --interface hapfluid_loopback --channel /tmp/hapfluid-left.sock --duration 2 --stats
  hapfluid-can-monitor --log run.blf --node 1 --json
"""
from __future__ import annotations

import argparse
import collections
import json
import pathlib
import sys
import time

import can  # noqa: E402

from .paths import DBC as DEFAULT_DBC
from .proto import codec



class Decoder:
    """Frames in, protocol messages and problems out; keeps per-node statistics."""

    def __init__(self, nodes: set[int] | None, dbc=None):
        self.nodes = nodes
        self.dbc = dbc
        self.assemblers: dict[int, codec.CanAssembler] = {}
        self.counts = collections.Counter()
        self.bad = collections.Counter()
        self.errors = collections.Counter()
        self.first: dict = {}
        self.last: dict = {}

    def frame(self, msg: can.Message) -> list[dict]:
        if msg.is_error_frame:
            self.errors[msg.arbitration_id] += 1
            return [{"t": msg.timestamp, "error_frame": hex(msg.arbitration_id), "bus_off": bool(msg.arbitration_id & 0x40)}]
        if msg.is_extended_id or msg.arbitration_id > 0x1FF:
            return []  # not this protocol
        node = msg.arbitration_id & 0xF
        if node == 0 or (self.nodes and node not in self.nodes):
            return []
        out = {"t": msg.timestamp, "node": node, "id": msg.arbitration_id}
        if self.dbc is not None:
            try:
                out["signals"] = self.dbc.decode_message(msg.arbitration_id, bytes(msg.data), decode_choices=False)
            except (KeyError, ValueError) as err:
                out["dbc_error"] = str(err)
        try:
            if msg.is_fd:
                decoded = codec.canfd_decode(msg.arbitration_id, bytes(msg.data), node)
            else:
                assembler = self.assemblers.setdefault(node, codec.CanAssembler(node))
                decoded = assembler.feed(msg.arbitration_id, bytes(msg.data))
        except codec.WireError as err:
            self.bad[node] += 1
            out.update(bad=err.code, reason=str(err))
            return [out]
        if decoded is None:
            return [out] if self.dbc is not None else []  # a frame of an incomplete set
        key = (node, decoded["type"])
        self.counts[key] += 1
        self.first.setdefault(key, msg.timestamp)
        self.last[key] = msg.timestamp
        out.update(type=decoded["type"], seq=decoded["seq"], fields=decoded["fields"])
        return [out]

    def stats(self) -> dict:
        result = {}
        for (node, kind), n in sorted(self.counts.items()):
            span = self.last[(node, kind)] - self.first[(node, kind)]
            result.setdefault(str(node), {})[kind] = {"count": n, "rate_hz": round((n - 1) / span, 1) if span > 0 else None}
        for node, n in self.bad.items():
            result.setdefault(str(node), {})["bad_frames"] = n
        if self.errors:
            result["error_frames"] = sum(self.errors.values())
        return result


def text_line(item: dict) -> str:
    if "error_frame" in item:
        return f"{item['t']:.6f} ERROR FRAME {item['error_frame']}{' BUS-OFF' if item['bus_off'] else ''}"
    head = f"{item['t']:.6f} node {item['node']:2d} id {item['id']:03X}"
    if "bad" in item:
        return f"{head} BAD {item['bad']}: {item['reason']}"
    if "type" not in item:
        return f"{head} {item.get('signals', '')}"
    fields = " ".join(f"{k}={_short(v)}" for k, v in item["fields"].items())
    return f"{head} {item['type']} seq={item['seq']} {fields}"


def _short(value):
    if isinstance(value, list):
        return "(" + ",".join(f"{v:.4g}" for v in value) + ")"
    return value


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--channel", help="live: CAN interface (can0) or loopback socket path")
    src.add_argument("--log", type=pathlib.Path, help="recorded log: .log (candump -l), .asc, .blf, .csv, ...")
    p.add_argument("--interface", default="socketcan", help="python-can interface (default socketcan; "
                                                             "hapfluid_loopback for the loopback bus)")
    p.add_argument("--node", type=int, action="append", help="only these node ids (repeatable)")
    p.add_argument("--dbc", type=pathlib.Path, default=DEFAULT_DBC)
    p.add_argument("--signals", action="store_true", help="also show every frame's DBC signals")
    p.add_argument("--duration", type=float, help="live: stop after this many seconds")
    p.add_argument("--count", type=int, help="stop after this many frames")
    p.add_argument("--json", action="store_true", help="one JSON object per line")
    p.add_argument("--stats", action="store_true", help="print per-node message counts and rates at the end")
    p.add_argument("--quiet", action="store_true", help="no per-message output (with --stats)")
    args = p.parse_args(argv)

    dbc = None
    if args.signals:
        # Only --signals needs cantools, which Debian 12 does not package: the project venv has
        # it; on an installed rig, `pip install cantools` (in a venv) adds it.
        try:
            import cantools
        except ModuleNotFoundError:
            p.error("--signals needs the cantools package, which this Python lacks (pip install cantools)")
        dbc = cantools.database.load_file(str(args.dbc))
    decoder = Decoder(set(args.node) if args.node else None, dbc)
    if args.log:
        if not args.log.exists():
            p.error(f"--log {args.log}: no such file")
        frames = can.LogReader(str(args.log))
        bus = None
    else:
        try:
            bus = can.Bus(interface=args.interface, channel=args.channel, fd=True)
        except (OSError, can.CanError) as err:
            print(f"can_monitor: cannot open {args.interface} {args.channel}: {err}", file=sys.stderr)
            if args.interface == "socketcan":
                print("  (SocketCAN needs a kernel with can-raw and an interface that is up: "
                      "ip link add vcan0 type vcan; ip link set up vcan0)", file=sys.stderr)
            return 2
        frames = _live(bus, args.duration)
    seen = 0
    try:
        for msg in frames:
            for item in decoder.frame(msg):
                if not args.quiet:
                    print(json.dumps(item) if args.json else text_line(item), flush=False)
            seen += 1
            if args.count and seen >= args.count:
                break
    except KeyboardInterrupt:
        pass
    finally:
        if bus is not None:
            bus.shutdown()
    if args.stats:
        stats = decoder.stats()
        print(json.dumps({"stats": stats}) if args.json else json.dumps(stats, indent=1))
    return 0


def _live(bus, duration):
    end = None if duration is None else time.monotonic() + duration
    while end is None or time.monotonic() < end:
        msg = bus.recv(timeout=0.1 if end is None else max(0.0, min(0.1, end - time.monotonic())))
        if msg is not None:
            yield msg


if __name__ == "__main__":
    sys.exit(main())
