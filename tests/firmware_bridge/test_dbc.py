"""The DBC file says what the codec does: cantools decodes every test-vector frame (classic and
CAN FD) into the same values as the codec, so candump + cantools on a rig shows the true wrench."""
import json
import subprocess
import sys

import cantools
import pytest

from proto_path import DBC, SOURCE_DIR, VECTORS

V = json.loads(VECTORS.read_text())
DB = cantools.database.load_file(str(DBC))


def test_committed_dbc_is_up_to_date():
    subprocess.run([sys.executable, str(SOURCE_DIR / "firmware_bridge/dbc/generate_dbc.py"), "--check"], check=True)


def signals_as_fields(signals: dict) -> dict:
    """Maps DBC signal names back to codec fields (the quaternion stays in smallest-three form)."""
    out = {}
    for prefix, field in (("position", "position_m"), ("velocity", "linear_velocity_m_s"),
                          ("angular_velocity", "angular_velocity_rad_s"), ("force", "force_n"),
                          ("torque", "torque_nm")):
        if f"{prefix}_x" in signals:
            out[field] = [signals[f"{prefix}_{a}"] for a in "xyz"]
    for name in ("command_echo", "buttons", "status", "fault", "faults", "cause", "detail", "reason", "uptime_ms",
                 "vendor_id", "product_id", "firmware_version", "watchdog_ms", "device_time_us"):
        if name in signals:
            out[name] = signals[name]
    if "max_force" in signals:
        out.update(max_force_n=signals["max_force"], max_torque_nm=signals["max_torque"],
                   workspace_half_extent_m=signals["workspace_half_extent"])
    if "enable" in signals:
        out["flags"] = signals["enable"] | signals["estop"] << 1 | signals["clear_faults"] << 2
    if "quat_largest" in signals:
        small = [signals["quat_a"], signals["quat_b"], signals["quat_c"]]
        out["quat_small"] = small
        out["quat_largest"] = signals["quat_largest"]
    return out


def expected_fields(vector: dict, signals: dict, classic: bool) -> dict:
    d = dict(vector["decoded"])
    if "orientation" in d:
        # smallest three: the DBC shows the three components the codec kept, in order
        q = d.pop("orientation")
        largest = signals["quat_largest"]
        assert abs(q[largest]) >= max(abs(c) for c in q) - 1e-4
        d["quat_small"] = [q[i] for i in range(4) if i != largest]
        d["quat_largest"] = largest
        if classic:
            d.pop("device_time_us")
            d.pop("fault")
    if vector["message"]["type"] == "INFO":
        d.pop("protocol_version")
    return d


def assert_same(got: dict, want: dict, name: str):
    assert set(want) <= set(got), f"{name}: DBC lacks {set(want) - set(got)}"
    for key, value in want.items():
        if isinstance(value, list):
            assert got[key] == pytest.approx(value, abs=1e-12), f"{name}: {key}"
        else:
            assert got[key] == pytest.approx(value, abs=1e-12), f"{name}: {key}"


@pytest.mark.parametrize("vector", V["valid"], ids=lambda v: v["name"])
def test_cantools_decodes_classic_frames_like_the_codec(vector):
    signals = {}
    for frame in vector["can"]:
        message = DB.get_message_by_frame_id(frame["id"])
        assert not message.is_fd
        assert message.name.endswith(f"_N{vector['node']}")
        signals.update(DB.decode_message(frame["id"], bytes.fromhex(frame["data"]), decode_choices=False))
    assert signals["seq8"] == vector["message"]["seq"] & 0xFF
    assert_same(signals_as_fields(signals), expected_fields(vector, signals, classic=True), vector["name"])


@pytest.mark.parametrize("vector", V["valid"], ids=lambda v: v["name"])
def test_cantools_decodes_canfd_frames_like_the_codec(vector):
    fd = vector["canfd"]
    message = DB.get_message_by_frame_id(fd["id"])
    assert message.is_fd and message.length == len(bytes.fromhex(fd["data"]))
    signals = DB.decode_message(fd["id"], bytes.fromhex(fd["data"]), decode_choices=False)
    assert signals["version"] == 1 and signals["seq"] == vector["message"]["seq"]
    assert_same(signals_as_fields(signals), expected_fields(vector, signals, classic=False), vector["name"])
