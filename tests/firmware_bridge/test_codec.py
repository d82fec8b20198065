"""The Python codec against the shared vectors the C codec also passes (test_vectors.cpp), plus
properties: round trips within half a step (the wrench within one, never past its value), every malformed input rejected for its reason."""
import json
import math
import subprocess
import sys

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from proto_path import SOURCE_DIR, VECTORS
from hapfluid.proto import codec

V = json.loads(VECTORS.read_text())


def test_committed_vectors_are_what_the_python_codec_produces():
    # generate.py --check rebuilds every vector with the Python codec and compares to the file
    # the C test reads: a codec change that forgets the other language fails here or there.
    subprocess.run([sys.executable, str(SOURCE_DIR / "firmware_bridge/test_vectors/generate.py"), "--check"],
                   check=True)


@pytest.mark.parametrize("vector", V["valid"], ids=lambda v: v["name"])
def test_valid_vector_encodes_and_decodes_on_every_framing(vector):
    msg, node = vector["message"], vector["node"]
    assert codec.encode_packet(msg).hex() == vector["packet"]
    decoded = codec.decode_packet(bytes.fromhex(vector["packet"]))
    assert decoded["fields"] == vector["decoded"]
    fd_id, fd_data = codec.canfd_encode(msg, node)
    assert (fd_id, fd_data.hex()) == (vector["canfd"]["id"], vector["canfd"]["data"])
    assert codec.canfd_decode(fd_id, fd_data, node)["fields"] == vector["decoded"]
    frames = codec.can_encode(msg, node)
    assert [(i, d.hex()) for i, d in frames] == [(f["id"], f["data"]) for f in vector["can"]]
    assembler = codec.CanAssembler(node)
    results = [assembler.feed(i, d) for i, d in frames]
    assert all(r is None for r in results[:-1])
    expected = dict(vector["decoded"])
    if msg["type"] == "STATE":  # classic CAN does not carry the device clock or the fault byte
        expected.update(device_time_us=0, fault=0)
    assert results[-1]["fields"] == expected
    assert results[-1]["seq"] == msg["seq"] & 0xFF


@pytest.mark.parametrize("vector", V["malformed_packets"], ids=lambda v: v["name"])
def test_malformed_packet_rejected_for_its_reason(vector):
    with pytest.raises(codec.WireError) as err:
        codec.decode_packet(bytes.fromhex(vector["bytes"]))
    assert err.value.code == vector["error"]


@pytest.mark.parametrize("vector", V["malformed_can"], ids=lambda v: v["name"])
def test_malformed_classic_frames_rejected_for_their_reason(vector):
    assembler = codec.CanAssembler(vector["node"])
    with pytest.raises(codec.WireError) as err:
        for frame in vector["frames"]:
            assembler.feed(frame["id"], bytes.fromhex(frame["data"]))
    assert err.value.code == vector["error"]


finite = st.floats(allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None)
@given(force=st.lists(st.floats(-32.7, 32.7), min_size=3, max_size=3),
       torque=st.lists(st.floats(-3.27, 3.27), min_size=3, max_size=3),
       flags=st.integers(0, 7), seq=st.integers(0, 65535))
@example(force=[9.9995, -9.9995, 0.0015], torque=[0.49995, -0.49995, 0.00015], flags=1, seq=0)
def test_command_round_trip_within_a_step_and_never_past_the_value(force, torque, flags, seq):
    # the safety layer limited this wrench: the wire may make it smaller, never larger
    msg = {"type": "COMMAND", "seq": seq, "fields": {"force_n": force, "torque_nm": torque, "flags": flags}}
    got = codec.decode_packet(codec.encode_packet(msg))
    assert got["seq"] == seq and got["fields"]["flags"] == flags
    for a, b in zip(got["fields"]["force_n"], force):
        assert abs(a) <= abs(b) and abs(a - b) < 1e-3  # 1 mN steps
    for a, b in zip(got["fields"]["torque_nm"], torque):
        assert abs(a) <= abs(b) and abs(a - b) < 1e-4  # 0.1 mN.m steps


@settings(max_examples=300, deadline=None)
@given(q=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: sum(c * c for c in q) > 0.01))
def test_any_orientation_survives_smallest_three_within_1e4(q):
    norm = math.sqrt(sum(c * c for c in q))
    q = [c / norm for c in q]
    msg = {"type": "STATE", "seq": 1, "fields": {"position_m": [0, 0, 0], "orientation": q,
                                                  "linear_velocity_m_s": [0, 0, 0], "angular_velocity_rad_s": [0, 0, 0]}}
    got = codec.decode_packet(codec.encode_packet(msg))["fields"]["orientation"]
    # q and -q are one rotation
    err = min(max(abs(a - b) for a, b in zip(got, q)), max(abs(a + b) for a, b in zip(got, q)))
    assert err < 1e-4


@settings(max_examples=200, deadline=None)
@given(value=finite.filter(lambda v: abs(v) > 32.7675) | st.just(float("nan")))
def test_unrepresentable_force_is_refused_not_clipped(value):
    msg = {"type": "COMMAND", "seq": 0, "fields": {"force_n": [0, value, 0], "torque_nm": [0, 0, 0], "flags": 1}}
    with pytest.raises(codec.WireError) as err:
        codec.encode_packet(msg)
    assert err.value.code == "RANGE"


@settings(max_examples=500, deadline=None)
@given(data=st.binary(max_size=80))
def test_random_bytes_never_crash_the_decoder(data):
    try:
        codec.decode_packet(data)
    except codec.WireError:
        pass
