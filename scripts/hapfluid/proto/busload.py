"""Bus-load budget of protocol v1 (the table in firmware_bridge/protocol.md comes from here).

Frame lengths follow ISO 11898-1 for 11-bit identifiers: nominal (no stuff bits) and worst case
(maximum dynamic stuffing). Run `python -m hapfluid.proto.busload` for the table.
"""
from __future__ import annotations

import math

# per device and per 1 ms tick; heartbeats add 1 frame per 100 ms each way
CLASSIC_FRAMES_PER_MS = {"STATE": (4, 8), "COMMAND": (2, 8)}
FD_FRAMES_PER_MS = {"STATE": 48, "COMMAND": 20}  # padded CAN FD data lengths


def classic_bits(data_bytes: int, worst: bool) -> int:
    stuffable = 1 + 11 + 1 + 1 + 1 + 4 + 8 * data_bytes + 15  # SOF..CRC
    fixed = stuffable + 1 + 2 + 7 + 3                        # CRC delimiter, ACK, EOF, IFS
    return fixed + ((stuffable - 1) // 4 if worst else 0)


def fd_time_us(data_bytes: int, nominal_bps: float, data_bps: float, worst: bool) -> float:
    arbitration = 1 + 11 + 1 + 1 + 1 + 1 + 1                 # SOF, ID, RRS, IDE, FDF, res, BRS
    crc = 17 if data_bytes <= 16 else 21
    data_phase = 1 + 4 + 8 * data_bytes + 4 + crc + math.ceil((4 + crc) / 4) + 1  # ESI..CRC delim, fixed stuff
    if worst:
        arbitration += (arbitration - 1) // 4
        data_phase += (1 + 4 + 8 * data_bytes) // 4
    tail = 2 + 7 + 3                                         # ACK, EOF, IFS at the nominal rate
    return (arbitration + tail) / nominal_bps * 1e6 + data_phase / data_bps * 1e6


def table() -> list[dict]:
    rows = []
    for worst in (False, True):
        bits = sum(n * classic_bits(b, worst) for n, b in CLASSIC_FRAMES_PER_MS.values())
        bits += 2 * classic_bits(8, worst) / 100
        us = bits / 1e6 * 1e6
        rows.append({"bus": "classic CAN 1 Mbit/s", "case": "worst" if worst else "nominal",
                     "frames_per_device_ms": 6.02, "us_per_device_ms": us, "load_per_device": us / 1000,
                     "devices_at_70pct": int(700 // us), "devices_at_100pct": int(1000 // us)})
        for data_rate in (2e6, 5e6):
            us = sum(fd_time_us(b, 1e6, data_rate, worst) for b in FD_FRAMES_PER_MS.values())
            us += 2 * fd_time_us(12, 1e6, data_rate, worst) / 100
            rows.append({"bus": f"CAN FD 1/{data_rate / 1e6:g} Mbit/s", "case": "worst" if worst else "nominal",
                         "frames_per_device_ms": 2.02, "us_per_device_ms": us, "load_per_device": us / 1000,
                         "devices_at_70pct": int(700 // us), "devices_at_100pct": int(1000 // us)})
    return rows


if __name__ == "__main__":
    print(f"{'bus':24} {'case':8} {'frames/ms':>9} {'us/ms':>7} {'load':>6} {'n@70%':>6} {'n@100%':>7}")
    for r in table():
        print(f"{r['bus']:24} {r['case']:8} {r['frames_per_device_ms']:9.2f} {r['us_per_device_ms']:7.1f} "
              f"{r['load_per_device']:6.1%} {r['devices_at_70pct']:6d} {r['devices_at_100pct']:7d}")
