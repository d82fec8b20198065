"""protocol.md, the codec and the DBC must say the same thing: the message table, the packet
lengths, the classic CAN function table and DLCs, the CAN FD lengths and the scalings are read
from the document and checked against the code, so an edit to one without the others fails."""
import re

import cantools
import pytest

from proto_path import DBC, SOURCE_DIR
from hapfluid.proto import codec

DOC = (SOURCE_DIR / "firmware_bridge" / "protocol.md").read_text()
DB = cantools.database.load_file(str(DBC))


def table_rows(pattern):
    return [m.groups() for m in re.finditer(pattern, DOC, re.MULTILINE)]


def test_message_table_matches_codec_types_and_packet_lengths():
    rows = table_rows(r"^\| (\d) \| ([A-Z_]+) \| [^|]+\| [^|]+\| (\d+) \|$")
    assert len(rows) == 8
    for type_id, name, length in rows:
        assert codec.TYPES[name] == int(type_id)
        assert codec.packet_length(int(type_id)) == int(length), name


def test_classic_can_table_matches_codec_functions_and_dbc():
    rows = table_rows(r"^\| (0x[0-9A-F]) \| ([A-Z_]+) \| (\d) \|")
    assert len(rows) == 13
    for function, name, dlc in rows:
        assert codec.FN[name] == int(function, 16), name
        message = DB.get_message_by_frame_id((int(function, 16) << 4) | 1)
        assert message.name == f"{name}_N1" and message.length == int(dlc) and not message.is_fd


@pytest.mark.parametrize("type_name", ["STATE", "COMMAND", "HOST_HEARTBEAT", "INFO_REQUEST", "INFO", "FAULT", "ESTOP"])
def test_canfd_lengths_in_the_dbc_are_the_padded_packets(type_name):
    type_id = codec.TYPES[type_name]
    size = next(s for s in codec.FD_SIZES if s >= codec.packet_length(type_id))
    message = DB.get_message_by_frame_id(codec.canfd_id(type_name, 1))
    assert message.is_fd and message.length == size


def test_scaling_table_matches_codec():
    scales = dict(table_rows(r"^\| ([a-zA-Z ]+?) (?:\([^)]*\) )?\| [^|]+\| (\d+) \|"))
    assert float(scales["position"]) == codec.SCALE_POSITION
    assert float(scales["orientation component"]) == codec.SCALE_QUAT
    assert float(scales["linear velocity"]) == codec.SCALE_VELOCITY
    assert float(scales["angular velocity"]) == codec.SCALE_ANGVEL
    assert float(scales["force"]) == codec.SCALE_FORCE
    assert float(scales["torque"]) == codec.SCALE_TORQUE
    assert float(scales["INFO max force"]) == codec.SCALE_INFO_FORCE


def test_crc_check_values_quoted_in_the_document():
    assert "0x29B1" in DOC and codec.crc16(b"123456789") == 0x29B1
    assert "0x4B" in DOC and codec.crc8(b"123456789") == 0x4B


def test_bus_load_table_is_what_busload_computes():
    from hapfluid.proto import busload
    rows = {(r["bus"], r["case"]): r for r in busload.table()}
    for bus, label in (("classic CAN 1 Mbit/s", "classic CAN, 1 Mbit/s"), ("CAN FD 1/2 Mbit/s", "CAN FD, 1 / 2 Mbit/s"),
                       ("CAN FD 1/5 Mbit/s", "CAN FD, 1 / 5 Mbit/s")):
        line = next(l for l in DOC.splitlines() if l.startswith(f"| {label} |"))
        nominal = rows[(bus, "nominal")]["us_per_device_ms"]
        worst = rows[(bus, "worst")]["us_per_device_ms"]
        assert f"| {nominal:.0f} (" in line and f"| {worst:.0f} (" in line, (line, nominal, worst)
    # the conclusion the document draws: classic CAN carries one device at 1 kHz, FD 1/5 carries 3
    assert rows[("classic CAN 1 Mbit/s", "worst")]["devices_at_100pct"] == 1
    assert rows[("CAN FD 1/5 Mbit/s", "worst")]["devices_at_70pct"] == 3
