"""hapfluid.can_monitor decodes live loopback traffic through the python-can adapter and recorded
logs in the formats CAN tools write (candump -l, Vector ASC, BLF), flagging damaged frames."""
import json
import subprocess
import sys

import can
import pytest

from proto_path import VECTORS
from fake_device import FakeDevice
from hapfluid.proto import codec, pycan_loopback


def monitor(*args):
    result = subprocess.run([sys.executable, "-m", "hapfluid.can_monitor", *map(str, args)], capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 0, result.stderr
    return [json.loads(line) for line in result.stdout.splitlines() if line.strip()]


def test_live_loopback_bus_shows_both_directions_at_1khz(binary, tmp_path):
    sock = tmp_path / "bus.sock"
    # generous run times: python's start-up on a loaded machine can take seconds; both programs
    # are stopped as soon as the monitor is done
    with FakeDevice(binary("haptic-fake-device"), sock, "--framing", "can", "--node", 4, duration=30):
        host = subprocess.Popen([str(binary("haptic-device-probe")), "--transport", "loopback", "--address",
                                 str(sock), "--framing", "can", "--node", "4", "--duration", "30", "--force",
                                 "0.5,0,0", "--enable"], stdout=subprocess.DEVNULL)
        try:
            lines = monitor("--interface", "hapfluid_loopback", "--channel", sock, "--duration", 1.0, "--stats",
                            "--json", "--quiet")
        finally:
            host.terminate()
            host.wait(timeout=10)
    stats = lines[-1]["stats"]["4"]
    # the monitor sees the device's 1 kHz states and the host's commands relayed by the bus, and
    # every frame set decodes. Rates are loose: the pure-Python decoder handles ~6000 frames/s and
    # may fall behind on a loaded CI machine (the C driver's rate is asserted in the e2e tests).
    assert stats["STATE"]["count"] > 300 and 300 < stats["STATE"]["rate_hz"] < 1100, stats
    assert stats["COMMAND"]["count"] > 300 and 300 < stats["COMMAND"]["rate_hz"] < 1100, stats
    assert "bad_frames" not in stats


def test_python_can_finds_the_adapter_through_the_packages_entry_point(binary, tmp_path):
    sock = tmp_path / "bus.sock"
    with FakeDevice(binary("haptic-fake-device"), sock, "--framing", "canfd", "--node", 2, duration=30):
        with can.Bus(interface="hapfluid_loopback", channel=str(sock)) as bus:
            # ask the device who it is, as a python-can script on a rig would
            fd_id, data = codec.canfd_encode({"type": "INFO_REQUEST", "seq": 0, "fields": {}}, 2)
            bus.send(can.Message(arbitration_id=fd_id, data=data, is_fd=True, is_extended_id=False))
            info = None
            for _ in range(200):
                msg = bus.recv(timeout=0.5)
                if msg is not None and msg.arbitration_id == codec.canfd_id("INFO", 2):
                    info = codec.canfd_decode(msg.arbitration_id, bytes(msg.data), 2)
                    break
    assert info is not None and info["fields"]["vendor_id"] == 0x1209


def test_adapter_without_a_bus_says_what_to_start(tmp_path):
    with pytest.raises(can.CanInterfaceNotImplementedError, match="haptic-fake-device"):
        pycan_loopback.LoopbackBus(channel=str(tmp_path / "none.sock"))


@pytest.mark.parametrize("suffix", [".log", ".asc", ".blf"])
def test_recorded_logs_decode_like_the_vectors_and_flag_damage(tmp_path, suffix):
    vectors = json.loads(VECTORS.read_text())["valid"]
    path = tmp_path / f"capture{suffix}"
    t = 1000.0
    with can.Logger(str(path)) as log:
        for v in vectors:
            for frame in v["can"]:
                t += 0.0001
                log.on_message_received(can.Message(timestamp=t, arbitration_id=frame["id"], is_extended_id=False,
                                                    data=bytes.fromhex(frame["data"]), channel="can0"))
        # one STATE set whose last frame (CRC-8) was damaged
        frames = vectors[1]["can"]
        for k, frame in enumerate(frames):
            data = bytearray.fromhex(frame["data"])
            if k == 3:
                data[7] ^= 0xFF
            t += 0.0001
            log.on_message_received(can.Message(timestamp=t, arbitration_id=frame["id"], is_extended_id=False,
                                                data=bytes(data), channel="can0"))
    items = monitor("--log", path, "--json")
    decoded = [i for i in items if "type" in i]
    assert [i["type"] for i in decoded] == [v["message"]["type"] for v in vectors]
    for item, v in zip(decoded, vectors):
        assert item["seq"] == v["message"]["seq"] & 0xFF
        if v["message"]["type"] == "COMMAND":
            assert item["fields"]["force_n"] == v["decoded"]["force_n"]
    bad = [i for i in items if "bad" in i]
    assert len(bad) == 1 and bad[0]["bad"] == "CRC"
