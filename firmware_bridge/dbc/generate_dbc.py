#!/usr/bin/env python3
"""Writes hapfluid.dbc: every classic CAN and CAN FD frame of protocol v1 for nodes 1..15, so
candump, cantools, SavvyCAN or any DBC-aware tool decodes live traffic. The layouts here are the
ones of protocol.md; tests/firmware_bridge/test_dbc.py decodes every test vector with cantools and
compares with the Python codec. `--check` fails when the committed file is out of date."""
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
Q = 1.0 / 32767.0

# (name, start bit, length, signed, factor, minimum, maximum, unit); little endian ("@1")
SEQ8 = ("seq8", 0, 8, False, 1, 0, 255, "")
CLASSIC = [  # function, name, dlc, sender, signals
    (0x1, "ESTOP", 2, "HOST", [SEQ8, ("reason", 8, 8, False, 1, 0, 2, "")]),
    (0x2, "FAULT", 8, "DEVICE", [SEQ8, ("faults", 8, 8, False, 1, 0, 63, ""), ("cause", 16, 8, False, 1, 0, 5, ""),
                                 ("detail", 32, 32, False, 1, 0, 4294967295, "")]),
    (0x3, "CMD_FORCE", 8, "HOST", [SEQ8] + [(f"force_{a}", 8 + 16 * i, 16, True, 0.001, -32.767, 32.767, "N")
                                            for i, a in enumerate("xyz")]
     + [("enable", 56, 1, False, 1, 0, 1, ""), ("estop", 57, 1, False, 1, 0, 1, ""),
        ("clear_faults", 58, 1, False, 1, 0, 1, "")]),
    (0x4, "CMD_TORQUE", 8, "HOST", [SEQ8] + [(f"torque_{a}", 8 + 16 * i, 16, True, 0.0001, -3.2767, 3.2767, "Nm")
                                             for i, a in enumerate("xyz")] + [("crc8", 56, 8, False, 1, 0, 255, "")]),
    (0x5, "STATE_POS", 8, "DEVICE", [SEQ8] + [(f"position_{a}", 8 + 16 * i, 16, True, 2e-05, -0.65534, 0.65534, "m")
                                              for i, a in enumerate("xyz")]
     + [("command_echo", 56, 8, False, 1, 0, 255, "")]),
    (0x6, "STATE_ROT", 8, "DEVICE", [SEQ8] + [(f"quat_{a}", 8 + 16 * i, 16, True, Q, -0.7071, 0.7071, "")
                                              for i, a in enumerate("abc")]
     + [("quat_largest", 56, 2, False, 1, 0, 3, ""), ("buttons", 58, 6, False, 1, 0, 63, "")]),
    (0x7, "STATE_VEL", 8, "DEVICE", [SEQ8] + [(f"velocity_{a}", 8 + 16 * i, 16, True, 0.0001, -3.2767, 3.2767, "m/s")
                                              for i, a in enumerate("xyz")]
     + [("status", 56, 8, False, 1, 0, 63, "")]),
    (0x8, "STATE_ANGVEL", 8, "DEVICE", [SEQ8] + [(f"angular_velocity_{a}", 8 + 16 * i, 16, True, 0.001, -32.767,
                                                  32.767, "rad/s") for i, a in enumerate("xyz")]
     + [("crc8", 56, 8, False, 1, 0, 255, "")]),
    (0x9, "DEVICE_HEARTBEAT", 8, "DEVICE", [SEQ8, ("status", 8, 8, False, 1, 0, 63, ""),
                                            ("uptime_ms", 16, 32, False, 1, 0, 4294967295, "ms"),
                                            ("protocol_version", 48, 8, False, 1, 0, 255, "")]),
    (0xA, "HOST_HEARTBEAT", 8, "HOST", [SEQ8, ("status", 8, 8, False, 1, 0, 63, ""),
                                        ("uptime_ms", 16, 32, False, 1, 0, 4294967295, "ms"),
                                        ("protocol_version", 48, 8, False, 1, 0, 255, "")]),
    (0xB, "INFO_REQUEST", 1, "HOST", [SEQ8]),
    (0xC, "INFO_A", 8, "DEVICE", [SEQ8, ("vendor_id", 8, 16, False, 1, 0, 65535, ""),
                                  ("product_id", 24, 16, False, 1, 0, 65535, ""),
                                  ("firmware_version", 40, 16, False, 1, 0, 65535, ""),
                                  ("protocol_version", 56, 8, False, 1, 0, 255, "")]),
    (0xD, "INFO_B", 8, "DEVICE", [SEQ8, ("max_force", 8, 16, False, 0.01, 0, 655.35, "N"),
                                  ("max_torque", 24, 16, False, 0.001, 0, 65.535, "Nm"),
                                  ("workspace_half_extent", 40, 16, False, 0.001, 0, 65.535, "m"),
                                  ("watchdog_ms", 56, 8, False, 1, 1, 255, "ms")]),
]

HEADER = [("version", 0, 8, False, 1, 1, 1, ""), ("type", 8, 8, False, 1, 1, 8, ""),
          ("seq", 16, 16, False, 1, 0, 65535, "")]


def crc16_at(byte):
    return [("crc16", 8 * byte, 16, False, 1, 0, 65535, "")]


def fd_state():
    s = [("device_time_us", 32, 32, False, 1, 0, 4294967295, "us")]
    s += [(f"position_{a}", 64 + 16 * i, 16, True, 2e-05, -0.65534, 0.65534, "m") for i, a in enumerate("xyz")]
    s += [("command_echo", 112, 8, False, 1, 0, 255, "")]
    s += [(f"quat_{a}", 120 + 16 * i, 16, True, Q, -0.7071, 0.7071, "") for i, a in enumerate("abc")]
    s += [("quat_largest", 168, 2, False, 1, 0, 3, ""), ("buttons", 170, 6, False, 1, 0, 63, "")]
    s += [(f"velocity_{a}", 176 + 16 * i, 16, True, 0.0001, -3.2767, 3.2767, "m/s") for i, a in enumerate("xyz")]
    s += [("status", 224, 8, False, 1, 0, 63, "")]
    s += [(f"angular_velocity_{a}", 232 + 16 * i, 16, True, 0.001, -32.767, 32.767, "rad/s")
          for i, a in enumerate("xyz")]
    return s + [("fault", 280, 8, False, 1, 0, 63, "")] + crc16_at(36)


FD = [  # first classic function, name, padded size, sender, payload signals
    (0x5, "FD_STATE", 48, "DEVICE", fd_state()),
    (0x3, "FD_COMMAND", 20, "HOST",
     [(f"force_{a}", 32 + 16 * i, 16, True, 0.001, -32.767, 32.767, "N") for i, a in enumerate("xyz")]
     + [(f"torque_{a}", 80 + 16 * i, 16, True, 0.0001, -3.2767, 3.2767, "Nm") for i, a in enumerate("xyz")]
     + [("enable", 128, 1, False, 1, 0, 1, ""), ("estop", 129, 1, False, 1, 0, 1, ""),
        ("clear_faults", 130, 1, False, 1, 0, 1, "")] + crc16_at(18)),
    (0xA, "FD_HOST_HEARTBEAT", 12, "HOST", [("uptime_ms", 32, 32, False, 1, 0, 4294967295, "ms"),
                                            ("status", 64, 8, False, 1, 0, 63, "")] + crc16_at(10)),
    (0x9, "FD_DEVICE_HEARTBEAT", 12, "DEVICE", [("uptime_ms", 32, 32, False, 1, 0, 4294967295, "ms"),
                                                ("status", 64, 8, False, 1, 0, 63, "")] + crc16_at(10)),
    (0xB, "FD_INFO_REQUEST", 6, "HOST", crc16_at(4)),
    (0xC, "FD_INFO", 20, "DEVICE", [("vendor_id", 32, 16, False, 1, 0, 65535, ""),
                                    ("product_id", 48, 16, False, 1, 0, 65535, ""),
                                    ("firmware_version", 64, 16, False, 1, 0, 65535, ""),
                                    ("protocol_version", 80, 8, False, 1, 0, 255, ""),
                                    ("watchdog_ms", 88, 8, False, 1, 1, 255, "ms"),
                                    ("max_force", 96, 16, False, 0.01, 0, 655.35, "N"),
                                    ("max_torque", 112, 16, False, 0.001, 0, 65.535, "Nm"),
                                    ("workspace_half_extent", 128, 16, False, 0.001, 0, 65.535, "m")] + crc16_at(18)),
    (0x2, "FD_FAULT", 12, "DEVICE", [("faults", 32, 8, False, 1, 0, 63, ""), ("cause", 40, 8, False, 1, 0, 5, ""),
                                     ("detail", 48, 32, False, 1, 0, 4294967295, "")] + crc16_at(10)),
    (0x1, "FD_ESTOP", 8, "HOST", [("reason", 32, 8, False, 1, 0, 2, "")] + crc16_at(6)),
]


def fmt(v):
    return repr(float(v)) if isinstance(v, float) else str(v)


def message(can_id, name, size, sender, signals):
    receiver = "HOST" if sender == "DEVICE" else "DEVICE"
    lines = [f"BO_ {can_id} {name}: {size} {sender}"]
    for sig, start, length, signed, factor, lo, hi, unit in signals:
        lines.append(f' SG_ {sig} : {start}|{length}@1{"-" if signed else "+"} ({fmt(factor)},0) '
                     f'[{fmt(lo)}|{fmt(hi)}] "{unit}" {receiver}')
    return "\n".join(lines) + "\n"


def build():
    out = ['VERSION "hapfluid wire protocol v1"', "", "NS_ :", "    VFrameFormat", "", "BS_:", "",
           "BU_: HOST DEVICE", ""]
    fd_ids = []
    for node in range(1, 16):
        for function, name, dlc, sender, signals in CLASSIC:
            out.append(message((function << 4) | node, f"{name}_N{node}", dlc, sender, signals))
        for function, name, size, sender, signals in FD:
            can_id = ((0x10 | function) << 4) | node
            fd_ids.append(can_id)
            out.append(message(can_id, f"{name}_N{node}", size, sender, HEADER + signals))
    out.append('CM_ "hapfluid haptic device protocol v1 (firmware_bridge/protocol.md). Classic CAN id = '
               'function << 4 | node; CAN FD id = (0x10 | function) << 4 | node. Multi-frame messages share '
               'seq8; the STATE and COMMAND frame sets end with a CRC-8/SAE-J1850, CAN FD frames carry the '
               'whole packet with its CRC-16/CCITT-FALSE.";')
    out.append('BA_DEF_ BO_ "VFrameFormat" ENUM "StandardCAN","ExtendedCAN","reserved","J1939PG","reserved",'
               '"reserved","reserved","reserved","reserved","reserved","reserved","reserved","reserved",'
               '"reserved","StandardCAN_FD","ExtendedCAN_FD";')
    out.append('BA_DEF_DEF_ "VFrameFormat" "StandardCAN";')
    out += [f'BA_ "VFrameFormat" BO_ {i} 14;' for i in fd_ids]
    return "\n".join(out) + "\n"


def main():
    path = HERE / "hapfluid.dbc"
    text = build()
    if "--check" in sys.argv:
        if path.read_text() != text:
            sys.exit(f"{path} is out of date: rerun {__file__}")
        return
    path.write_text(text)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
