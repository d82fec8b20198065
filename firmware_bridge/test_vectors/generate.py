#!/usr/bin/env python3
"""Writes vectors.json: messages with their exact bytes on every framing, and malformed inputs
with the rule that rejects them. The C codec (tests/firmware_bridge/test_vectors.cpp) and the
Python codec (tests/firmware_bridge/test_codec.py) must both reproduce this file exactly;
`generate.py --check` fails when the committed file and the Python codec disagree."""
import json
import math
import pathlib
import sys

from hapfluid.proto import codec

HERE = pathlib.Path(__file__).resolve().parent
S = math.sqrt(0.5)


def state(seq, pos, quat, vel, angvel, echo=0, buttons=0, status=0, fault=0, time_us=0):
    return {"type": "STATE", "seq": seq, "fields": {
        "device_time_us": time_us, "position_m": pos, "orientation": quat, "linear_velocity_m_s": vel,
        "angular_velocity_rad_s": angvel, "command_echo": echo, "buttons": buttons, "status": status,
        "fault": fault}}


def command(seq, force, torque, flags):
    return {"type": "COMMAND", "seq": seq, "fields": {"force_n": force, "torque_nm": torque, "flags": flags}}


VALID = [
    ("state_at_rest_home", 3, state(0, [0, 0, 0], [1, 0, 0, 0], [0, 0, 0], [0, 0, 0])),
    ("state_moving_buttons_status", 1, state(513, [0.1234, -0.05, 0.3], [0.9238795, 0.3826834, 0, 0],
                                             [0.25, -1.5, 0.0001], [1.0, -2.5, 30.0], echo=200, buttons=0x21,
                                             status=0x11, fault=0, time_us=123456789)),
    ("state_limits_of_range", 15, state(65535, [0.65534, -0.65534, 0.00001], [0, 0, 0, 1], [3.2767, -3.2767, 0],
                                        [32.767, -32.767, 0], echo=255, buttons=0x3F, status=0x3F, fault=0x3F,
                                        time_us=0xFFFFFFFF)),
    ("state_half_lsb_rounds_away_from_zero", 2, state(7, [0.00001, -0.00001, 0.00003], [S, 0, S, 0],
                                                      [0.00005, -0.00005, 0], [0.0005, -0.0005, 0])),
    ("state_quaternion_largest_negative", 4, state(8, [0, 0, 0], [-0.1, 0.2, -0.9, 0.3756328], [0, 0, 0], [0, 0, 0])),
    ("state_spin_half_turn", 5, state(9, [0.01, 0.02, 0.03], [0.0, 0.0, 0.0, -1.0], [0, 0, 0], [0, 0, 6.283])),
    ("command_zero_disabled", 3, command(0, [0, 0, 0], [0, 0, 0], 0)),
    ("command_enabled_wrench", 3, command(4242, [1.5, -2.25, 9.999], [0.1, -0.0501, 0.3333], 1)),
    ("command_full_scale_estop_clear", 7, command(65535, [32.767, -32.767, 0], [3.2767, -3.2767, 0], 6)),
    # a limited wrench half a step below a whole mN or 0.1 mN.m: rounded toward zero, never past it
    ("command_half_lsb_never_rounds_past_the_value", 3,
     command(5, [9.9995, -9.9995, 0.0015], [0.49995, -0.49995, 0.00015], 1)),
    ("host_heartbeat", 3, {"type": "HOST_HEARTBEAT", "seq": 12, "fields": {"uptime_ms": 1000, "status": 0}}),
    ("device_heartbeat", 3, {"type": "DEVICE_HEARTBEAT", "seq": 300, "fields": {"uptime_ms": 86400000, "status": 3}}),
    ("info_request", 3, {"type": "INFO_REQUEST", "seq": 1, "fields": {}}),
    ("info", 3, {"type": "INFO", "seq": 1, "fields": {
        "vendor_id": 0x1209, "product_id": 0x4846, "firmware_version": 0x0102, "protocol_version": 1,
        "watchdog_ms": 20, "max_force_n": 12.5, "max_torque_nm": 0.75, "workspace_half_extent_m": 0.3}}),
    # a device's limits are reported at or below what they are, never above
    ("info_limits_never_round_up", 3, {"type": "INFO", "seq": 2, "fields": {
        "vendor_id": 0x1209, "product_id": 0x4846, "firmware_version": 0x0102, "protocol_version": 1,
        "watchdog_ms": 20, "max_force_n": 9.996, "max_torque_nm": 0.4996, "workspace_half_extent_m": 0.2996}}),
    ("fault_watchdog", 3, {"type": "FAULT", "seq": 17, "fields": {"faults": 1, "cause": 0, "detail": 21}}),
    ("fault_estop_and_workspace", 9, {"type": "FAULT", "seq": 18, "fields": {"faults": 0x0A, "cause": 3, "detail": 0}}),
    ("estop_operator", 3, {"type": "ESTOP", "seq": 2, "fields": {"reason": 0}}),
    ("estop_link_loss", 3, {"type": "ESTOP", "seq": 3, "fields": {"reason": 2}}),
]


def hexs(b):
    return bytes(b).hex()


def valid_vector(name, node, msg):
    packet = codec.encode_packet(msg)
    fd_id, fd_data = codec.canfd_encode(msg, node)
    frames = codec.can_encode(msg, node)
    return {"name": name, "node": node, "message": msg, "packet": hexs(packet),
            "decoded": codec.decode_packet(packet)["fields"],
            "canfd": {"id": fd_id, "data": hexs(fd_data)},
            "can": [{"id": i, "data": hexs(d)} for i, d in frames]}


def with_crc(body):
    return body + codec.crc16(body).to_bytes(2, "little")


def malformed_packets():
    good_state = codec.encode_packet(VALID[1][2])
    good_cmd = codec.encode_packet(VALID[7][2])
    out = []

    def add(name, data, error):
        out.append({"name": name, "bytes": hexs(data), "error": error})

    add("empty", b"", "SHORT")
    add("header_only", good_state[:4], "SHORT")
    add("state_truncated", good_state[:-1], "SHORT")
    add("state_trailing_garbage", good_state + b"\x01", "LENGTH")
    add("wrong_version", bytes([2]) + good_state[1:], "VERSION")
    add("version_zero", with_crc(bytes([0]) + good_state[1:-2]), "VERSION")
    add("unknown_type", with_crc(bytes([1, 0x42, 0, 0])), "TYPE")
    add("bad_crc_flipped_bit", good_state[:10] + bytes([good_state[10] ^ 0x04]) + good_state[11:], "CRC")
    add("bad_crc_field", good_cmd[:-1] + bytes([good_cmd[-1] ^ 0xFF]), "CRC")
    body = bytearray(good_state[:-2]); body[4 + 4:4 + 6] = (-32768).to_bytes(2, "little", signed=True)
    add("position_reserved_minus_32768", with_crc(bytes(body)), "RANGE")
    body = bytearray(good_state[:-2]); body[4 + 11:4 + 13] = (23171).to_bytes(2, "little", signed=True)
    add("quaternion_component_beyond_sqrt_half", with_crc(bytes(body)), "RANGE")
    body = bytearray(good_state[:-2])
    for k in range(3):
        body[4 + 11 + 2 * k:4 + 13 + 2 * k] = (23000).to_bytes(2, "little", signed=True)
    add("quaternion_not_unit", with_crc(bytes(body)), "RANGE")
    body = bytearray(good_state[:-2]); body[4 + 24] |= 0x80
    add("state_status_reserved_bit", with_crc(bytes(body)), "RESERVED")
    body = bytearray(good_cmd[:-2]); body[4 + 12] |= 0x08
    add("command_flag_reserved_bit", with_crc(bytes(body)), "RESERVED")
    body = bytearray(good_cmd[:-2]); body[4 + 13] = 1
    add("command_reserved_byte", with_crc(bytes(body)), "RESERVED")
    body = bytearray(good_cmd[:-2]); body[4:6] = (-32768).to_bytes(2, "little", signed=True)
    add("command_force_reserved_minus_32768", with_crc(bytes(body)), "RANGE")
    add("fault_cause_out_of_range", with_crc(bytes([1, 7, 0, 0, 1, 9, 0, 0, 0, 0])), "RANGE")
    add("estop_reason_out_of_range", with_crc(bytes([1, 8, 0, 0, 7, 0])), "RANGE")
    add("info_watchdog_zero", with_crc(bytes([1, 6, 0, 0]) + bytes([9, 0x12, 0x46, 0x48, 1, 0, 1, 0]) + bytes(6)), "RANGE")
    return out


def malformed_can():
    node = 3
    state_frames = codec.can_encode(VALID[1][2], node)
    cmd_frames = codec.can_encode(VALID[7][2], node)
    out = []

    def add(name, frames, error):
        out.append({"name": name, "node": node, "frames": [{"id": i, "data": hexs(d)} for i, d in frames],
                    "error": error})

    corrupt = list(state_frames)
    corrupt[1] = (corrupt[1][0], corrupt[1][1][:3] + bytes([corrupt[1][1][3] ^ 1]) + corrupt[1][1][4:])
    add("state_frame_corrupted_crc8", corrupt, "CRC")
    corrupt = list(cmd_frames)
    corrupt[1] = (corrupt[1][0], corrupt[1][1][:7] + bytes([corrupt[1][1][7] ^ 0x55]))
    add("command_crc8_wrong", corrupt, "CRC")
    add("state_frame_short_dlc", [(state_frames[0][0], state_frames[0][1][:7])], "SHORT")
    add("estop_too_long", [(0x13, bytes([1, 0, 0]))], "LENGTH")
    add("heartbeat_wrong_version", [(0x93, bytes([1, 0, 0, 0, 0, 0, 2, 0]))], "VERSION")
    add("fault_reserved_byte", [(0x23, bytes([1, 1, 0, 9, 0, 0, 0, 0]))], "RESERVED")
    add("unknown_function", [(0xE3, bytes(8))], "CAN_ID")
    add("other_node_ignored", [(0x54, bytes(8))], "CAN_ID")
    return out


def build():
    return {"protocol_version": codec.PROTOCOL_VERSION,
            "about": "generated by firmware_bridge/test_vectors/generate.py; see firmware_bridge/protocol.md",
            "valid": [valid_vector(*v) for v in VALID],
            "malformed_packets": malformed_packets(),
            "malformed_can": malformed_can()}


def main():
    text = json.dumps(build(), indent=1) + "\n"
    path = HERE / "vectors.json"
    if "--check" in sys.argv:
        if path.read_text() != text:
            sys.exit(f"{path} differs from what the Python codec produces: rerun generate.py")
        return
    path.write_text(text)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
