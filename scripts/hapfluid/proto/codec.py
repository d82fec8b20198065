"""hapfluid wire protocol v1 in Python: the mirror of firmware_bridge/codec/src/codec.c.

Every arithmetic step (scaling, round-half-away-from-zero, the fixed-count Newton square root)
is the same IEEE-754 operation as in C, so both produce identical bytes; the shared test vectors
(firmware_bridge/test_vectors/vectors.json) check that. Messages are plain dicts:
  {"type": "STATE", "seq": 7, "fields": {...}}
"""
from __future__ import annotations

import struct

PROTOCOL_VERSION = 1

TYPES = {"STATE": 1, "COMMAND": 2, "HOST_HEARTBEAT": 3, "DEVICE_HEARTBEAT": 4,
         "INFO_REQUEST": 5, "INFO": 6, "FAULT": 7, "ESTOP": 8}
TYPE_NAMES = {v: k for k, v in TYPES.items()}
PAYLOAD = {1: 32, 2: 14, 3: 6, 4: 6, 5: 0, 6: 14, 7: 6, 8: 2}

# classic CAN function codes (id = function << 4 | node); CAN FD id = (0x10 | first) << 4 | node
FN = {"ESTOP": 0x1, "FAULT": 0x2, "CMD_FORCE": 0x3, "CMD_TORQUE": 0x4, "STATE_POS": 0x5,
      "STATE_ROT": 0x6, "STATE_VEL": 0x7, "STATE_ANGVEL": 0x8, "DEVICE_HEARTBEAT": 0x9,
      "HOST_HEARTBEAT": 0xA, "INFO_REQUEST": 0xB, "INFO_A": 0xC, "INFO_B": 0xD}
FIRST_FN = {1: 0x5, 2: 0x3, 3: 0xA, 4: 0x9, 5: 0xB, 6: 0xC, 7: 0x2, 8: 0x1}

SCALE_POSITION = 50000.0
SCALE_QUAT = 32767.0
SCALE_VELOCITY = 10000.0
SCALE_ANGVEL = 1000.0
SCALE_FORCE = 1000.0
SCALE_TORQUE = 10000.0
SCALE_INFO_FORCE = 100.0
SCALE_INFO_TORQUE = 1000.0
SCALE_INFO_LENGTH = 1000.0
QUAT_SMALL_MAX = 23170

ERRORS = {0: "ok", -1: "short frame", -2: "wrong length", -3: "wrong protocol version",
          -4: "unknown message type", -5: "bad CRC", -6: "value out of range",
          -7: "reserved bits set", -8: "buffer too small", -9: "foreign CAN id",
          -10: "incomplete"}
ERROR_CODES = {"SHORT": -1, "LENGTH": -2, "VERSION": -3, "TYPE": -4, "CRC": -5, "RANGE": -6,
               "RESERVED": -7, "BUFFER": -8, "CAN_ID": -9, "INCOMPLETE": -10}
ERROR_NAMES = {v: k for k, v in ERROR_CODES.items()}


class WireError(ValueError):
    """A frame or message the protocol rejects; `code` names the rule (see ERROR_CODES)."""

    def __init__(self, code: str, detail: str = ""):
        self.code = code
        super().__init__(f"{ERRORS[ERROR_CODES[code]]}{': ' + detail if detail else ''}")


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def crc8(data: bytes) -> int:
    """CRC-8/SAE-J1850."""
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def _sqrt(x: float) -> float:
    if not x > 0:
        return 0.0
    y = x if x > 1 else 1.0
    for _ in range(64):
        y = 0.5 * (y + x / y)
    return y


def _quantise(value: float, scale: float, limit: int, what: str) -> int:
    if value != value:
        raise WireError("RANGE", f"{what} is NaN")
    scaled = value * scale
    if scaled > limit + 0.5 or scaled < -limit - 0.5:
        raise WireError("RANGE", f"{what} = {value} beyond +-{limit / scale}")
    q = int(scaled + 0.5) if scaled >= 0 else -int(-scaled + 0.5)
    if q > limit or q < -limit:
        raise WireError("RANGE", f"{what} = {value} beyond +-{limit / scale}")
    return q


def _quantise_within(value: float, scale: float, limit: int, what: str) -> int:
    """As _quantise, then one LSB back toward zero when rounding went past the value (codec.c)."""
    q = _quantise(value, scale, limit, what)
    if q > 0 and q / scale > value:
        q -= 1
    elif q < 0 and q / scale < value:
        q += 1
    return q


def _i16_within(value: float, scale: float, what: str) -> bytes:
    return struct.pack("<h", _quantise_within(value, scale, 32767, what))


def _i16(value: float, scale: float, what: str) -> bytes:
    return struct.pack("<h", _quantise(value, scale, 32767, what))


def _get_i16(data: bytes, offset: int, scale: float, what: str) -> float:
    (q,) = struct.unpack_from("<h", data, offset)
    if q == -32768:
        raise WireError("RANGE", f"{what} is -32768 (reserved)")
    return q / scale


def _u16(value: float, scale: float, what: str) -> bytes:
    if not value >= 0:
        raise WireError("RANGE", f"{what} = {value} must be >= 0")
    return struct.pack("<H", _quantise_within(value, scale, 65535, what))


def _put_quaternion(q_in) -> tuple[bytes, int]:
    norm2 = q_in[0] * q_in[0] + q_in[1] * q_in[1] + q_in[2] * q_in[2] + q_in[3] * q_in[3]
    if not (0.99 < norm2 < 1.01):
        raise WireError("RANGE", f"orientation norm^2 = {norm2} is not ~1")
    norm = _sqrt(norm2)
    q = [c / norm for c in q_in]
    largest = 0
    for i in range(4):
        if abs(q[i]) > abs(q[largest]):
            largest = i
    sign = -1.0 if q[largest] < 0 else 1.0
    out = b"".join(_i16(sign * q[i], SCALE_QUAT, "orientation") for i in range(4) if i != largest)
    return out, largest


def _get_quaternion(data: bytes, offset: int, qinfo: int) -> list[float]:
    largest = qinfo & 3
    small = []
    total = 0.0
    for k in range(3):
        (raw,) = struct.unpack_from("<h", data, offset + 2 * k)
        if raw > QUAT_SMALL_MAX or raw < -QUAT_SMALL_MAX:
            raise WireError("RANGE", f"orientation component {raw} beyond 1/sqrt(2)")
        value = raw / SCALE_QUAT
        small.append(value)
        total += value * value
    if total > 1.0:
        raise WireError("RANGE", "orientation components exceed a unit quaternion")
    dropped = _sqrt(1.0 - total)
    if any(abs(v) > dropped + 4.0 / SCALE_QUAT for v in small):
        raise WireError("RANGE", "orientation not in canonical form: the dropped component is not the largest")
    it = iter(small)
    return [dropped if i == largest else next(it) for i in range(4)]


def _check(cond: bool, code: str, detail: str) -> None:
    if cond:
        raise WireError(code, detail)


def write_payload(type_id: int, f: dict) -> bytes:
    if type_id == 1:
        buttons, status, fault = f.get("buttons", 0), f.get("status", 0), f.get("fault", 0)
        _check(buttons > 0x3F or status & 0xC0 or fault & 0xC0, "RESERVED", "state bits")
        out = struct.pack("<I", f.get("device_time_us", 0))
        out += b"".join(_i16(v, SCALE_POSITION, "position_m") for v in f["position_m"])
        out += bytes([f.get("command_echo", 0)])
        quat, largest = _put_quaternion(f["orientation"])
        out += quat + bytes([largest | (buttons << 2)])
        out += b"".join(_i16(v, SCALE_VELOCITY, "linear_velocity_m_s") for v in f["linear_velocity_m_s"])
        out += bytes([status])
        out += b"".join(_i16(v, SCALE_ANGVEL, "angular_velocity_rad_s") for v in f["angular_velocity_rad_s"])
        return out + bytes([fault])
    if type_id == 2:
        flags = f.get("flags", 0)
        _check(flags & 0xF8, "RESERVED", "command flags")
        out = b"".join(_i16_within(v, SCALE_FORCE, "force_n") for v in f["force_n"])
        out += b"".join(_i16_within(v, SCALE_TORQUE, "torque_nm") for v in f["torque_nm"])
        return out + bytes([flags, 0])
    if type_id in (3, 4):
        _check(f.get("status", 0) & 0xC0, "RESERVED", "heartbeat status")
        return struct.pack("<IBB", f["uptime_ms"], f.get("status", 0), 0)
    if type_id == 5:
        return b""
    if type_id == 6:
        _check(f["watchdog_ms"] == 0, "RANGE", "watchdog_ms = 0")
        out = struct.pack("<HHHBB", f["vendor_id"], f["product_id"], f["firmware_version"],
                          f["protocol_version"], f["watchdog_ms"])
        out += _u16(f["max_force_n"], SCALE_INFO_FORCE, "max_force_n")
        out += _u16(f["max_torque_nm"], SCALE_INFO_TORQUE, "max_torque_nm")
        return out + _u16(f["workspace_half_extent_m"], SCALE_INFO_LENGTH, "workspace_half_extent_m")
    if type_id == 7:
        _check(f["faults"] & 0xC0, "RESERVED", "fault bits")
        _check(f["cause"] > 5, "RANGE", "fault cause")
        return struct.pack("<BBI", f["faults"], f["cause"], f.get("detail", 0))
    if type_id == 8:
        _check(f["reason"] > 2, "RANGE", "estop reason")
        return bytes([f["reason"], 0])
    raise WireError("TYPE", f"type {type_id}")


def parse_payload(type_id: int, p: bytes) -> dict:
    if type_id == 1:
        _check(p[24] & 0xC0 or p[31] & 0xC0, "RESERVED", "state bits")
        return {
            "device_time_us": struct.unpack_from("<I", p, 0)[0],
            "position_m": [_get_i16(p, 4 + 2 * i, SCALE_POSITION, "position_m") for i in range(3)],
            "command_echo": p[10],
            "orientation": _get_quaternion(p, 11, p[17]),
            "buttons": p[17] >> 2,
            "linear_velocity_m_s": [_get_i16(p, 18 + 2 * i, SCALE_VELOCITY, "velocity") for i in range(3)],
            "status": p[24],
            "angular_velocity_rad_s": [_get_i16(p, 25 + 2 * i, SCALE_ANGVEL, "angular velocity") for i in range(3)],
            "fault": p[31],
        }
    if type_id == 2:
        _check(p[12] & 0xF8 or p[13], "RESERVED", "command flags")
        return {"force_n": [_get_i16(p, 2 * i, SCALE_FORCE, "force_n") for i in range(3)],
                "torque_nm": [_get_i16(p, 6 + 2 * i, SCALE_TORQUE, "torque_nm") for i in range(3)],
                "flags": p[12]}
    if type_id in (3, 4):
        _check(p[4] & 0xC0 or p[5], "RESERVED", "heartbeat")
        return {"uptime_ms": struct.unpack_from("<I", p, 0)[0], "status": p[4]}
    if type_id == 5:
        return {}
    if type_id == 6:
        _check(p[6] == 0 or p[7] == 0, "RANGE", "info protocol_version/watchdog_ms = 0")
        vendor, product, firmware, proto, watchdog, force, torque, extent = struct.unpack_from("<HHHBBHHH", p)
        return {"vendor_id": vendor, "product_id": product, "firmware_version": firmware,
                "protocol_version": proto, "watchdog_ms": watchdog,
                "max_force_n": force / SCALE_INFO_FORCE, "max_torque_nm": torque / SCALE_INFO_TORQUE,
                "workspace_half_extent_m": extent / SCALE_INFO_LENGTH}
    if type_id == 7:
        _check(p[0] & 0xC0, "RESERVED", "fault bits")
        _check(p[1] > 5, "RANGE", "fault cause")
        return {"faults": p[0], "cause": p[1], "detail": struct.unpack_from("<I", p, 2)[0]}
    if type_id == 8:
        _check(p[1] != 0, "RESERVED", "estop")
        _check(p[0] > 2, "RANGE", "estop reason")
        return {"reason": p[0]}
    raise WireError("TYPE", f"type {type_id}")


def packet_length(type_id: int) -> int:
    return 4 + PAYLOAD[type_id] + 2 if type_id in PAYLOAD else 0


def encode_packet(msg: dict) -> bytes:
    type_id = TYPES[msg["type"]]
    body = bytes([PROTOCOL_VERSION, type_id]) + struct.pack("<H", msg["seq"]) + write_payload(type_id, msg["fields"])
    return body + struct.pack("<H", crc16(body))


def decode_packet(data: bytes) -> dict:
    if len(data) < 6:
        raise WireError("SHORT", f"{len(data)} bytes")
    if data[0] != PROTOCOL_VERSION:
        raise WireError("VERSION", f"version {data[0]}")
    expected = packet_length(data[1])
    if expected == 0:
        raise WireError("TYPE", f"type {data[1]}")
    if len(data) < expected:
        raise WireError("SHORT", f"{len(data)} of {expected} bytes")
    if any(data[expected:]):
        raise WireError("LENGTH", "non-zero bytes after the packet")
    if crc16(data[:expected - 2]) != struct.unpack_from("<H", data, expected - 2)[0]:
        raise WireError("CRC", "packet CRC-16")
    return {"type": TYPE_NAMES[data[1]], "seq": struct.unpack_from("<H", data, 2)[0],
            "fields": parse_payload(data[1], data[4:expected - 2])}


# ---- CAN FD ----
FD_SIZES = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)


def canfd_id(type_name: str, node: int) -> int:
    return ((0x10 | FIRST_FN[TYPES[type_name]]) << 4) | node


def canfd_encode(msg: dict, node: int) -> tuple[int, bytes]:
    packet = encode_packet(msg)
    size = next(s for s in FD_SIZES if s >= len(packet))
    return canfd_id(msg["type"], node), packet + bytes(size - len(packet))


def canfd_decode(can_id: int, data: bytes, node: int) -> dict:
    if can_id > 0x7FF or can_id & 0xF != node or can_id >> 8 != 1:
        raise WireError("CAN_ID", hex(can_id))
    msg = decode_packet(bytes(data))
    if canfd_id(msg["type"], node) != can_id:
        raise WireError("TYPE", f"id {can_id:#x} does not carry {msg['type']}")
    return msg


# ---- classic CAN ----
def can_encode(msg: dict, node: int) -> list[tuple[int, bytes]]:
    if not 1 <= node <= 15:
        raise WireError("CAN_ID", f"node {node} not in 1..15")
    type_id = TYPES[msg["type"]]
    p = write_payload(type_id, msg["fields"])
    s = msg["seq"] & 0xFF

    def fid(name):
        return (FN[name] << 4) | node

    if type_id == 1:
        frames = [bytearray([s]) + p[4 + 7 * k: 11 + 7 * k] for k in range(4)]
        frames[3][7] = crc8(b"".join(frames)[:31])
        return [(fid(n), bytes(f)) for n, f in zip(("STATE_POS", "STATE_ROT", "STATE_VEL", "STATE_ANGVEL"), frames)]
    if type_id == 2:
        f0 = bytes([s]) + p[0:6] + p[12:13]
        f1 = bytes([s]) + p[6:12]
        return [(fid("CMD_FORCE"), f0), (fid("CMD_TORQUE"), f1 + bytes([crc8(f0 + f1)]))]
    if type_id in (3, 4):
        return [(fid(TYPE_NAMES[type_id]), bytes([s, p[4]]) + p[0:4] + bytes([PROTOCOL_VERSION, 0]))]
    if type_id == 5:
        return [(fid("INFO_REQUEST"), bytes([s]))]
    if type_id == 6:
        return [(fid("INFO_A"), bytes([s]) + p[0:7]), (fid("INFO_B"), bytes([s]) + p[8:14] + p[7:8])]
    if type_id == 7:
        return [(fid("FAULT"), bytes([s, p[0], p[1], 0]) + p[2:6])]
    if type_id == 8:
        return [(fid("ESTOP"), bytes([s, p[0]]))]
    raise WireError("TYPE", msg["type"])


class CanAssembler:
    """Reassembles classic CAN frames of one node into messages (mirror of hf_can_feed)."""

    GROUPS = {0x5: ("state", 0, 4), 0x6: ("state", 1, 4), 0x7: ("state", 2, 4), 0x8: ("state", 3, 4),
              0x3: ("command", 0, 2), 0x4: ("command", 1, 2), 0xC: ("info", 0, 2), 0xD: ("info", 1, 2)}

    def __init__(self, node: int):
        self.node = node
        self.pending = {"state": {}, "command": {}, "info": {}}

    def feed(self, can_id: int, data: bytes):
        """Returns a message dict, None while a multi-frame message is incomplete; raises WireError."""
        data = bytes(data)
        if can_id > 0xFF or can_id & 0xF != self.node:
            raise WireError("CAN_ID", hex(can_id))
        function = can_id >> 4
        if function in self.GROUPS:
            group, index, count = self.GROUPS[function]
            self._dlc(data, 8)
            slot = self.pending[group]
            if slot and next(iter(slot.values()))[0] != data[0]:
                slot.clear()
            slot[index] = data
            if len(slot) < count:
                return None
            frames = [slot[k] for k in range(count)]
            slot.clear()
            return self._complete(group, frames)
        if function in (0x9, 0xA):
            self._dlc(data, 8)
            _check(data[6] != PROTOCOL_VERSION, "VERSION", f"heartbeat version {data[6]}")
            _check(data[7] != 0, "RESERVED", "heartbeat")
            type_id = 3 if function == 0xA else 4
            return self._msg(type_id, data[0], data[2:6] + bytes([data[1], 0]))
        if function == 0xB:
            self._dlc(data, 1)
            return self._msg(5, data[0], b"")
        if function == 0x2:
            self._dlc(data, 8)
            _check(data[3] != 0, "RESERVED", "fault")
            return self._msg(7, data[0], data[1:3] + data[4:8])
        if function == 0x1:
            self._dlc(data, 2)
            return self._msg(8, data[0], bytes([data[1], 0]))
        raise WireError("CAN_ID", hex(can_id))

    @staticmethod
    def _dlc(data: bytes, wanted: int) -> None:
        if len(data) < wanted:
            raise WireError("SHORT", f"{len(data)} of {wanted} bytes")
        if len(data) > wanted:
            raise WireError("LENGTH", f"{len(data)} bytes, expected {wanted}")

    @staticmethod
    def _msg(type_id: int, seq8: int, payload: bytes) -> dict:
        return {"type": TYPE_NAMES[type_id], "seq": seq8, "fields": parse_payload(type_id, payload)}

    def _complete(self, group: str, frames: list[bytes]) -> dict:
        seq8 = frames[0][0]
        if group == "state":
            joined = b"".join(frames)
            if crc8(joined[:31]) != joined[31]:
                raise WireError("CRC", "state CRC-8")
            payload = bytes(4) + b"".join(f[1:8] for f in frames)
            return self._msg(1, seq8, payload[:31] + b"\0")
        if group == "command":
            if crc8(frames[0] + frames[1][:7]) != frames[1][7]:
                raise WireError("CRC", "command CRC-8")
            return self._msg(2, seq8, frames[0][1:7] + frames[1][1:7] + frames[0][7:8] + b"\0")
        return self._msg(6, seq8, frames[0][1:8] + frames[1][7:8] + frames[1][1:7])
