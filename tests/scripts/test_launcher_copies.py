"""The launcher's copies of a scene and a rig (hapfluid.launcher), read and written as TOML:
the fake devices' scene keeps every table of the original with its motions later by the lead-in,
its hands in their device frame and its meshes found from anywhere; the rig keeps every device
with loopback sockets private to the run."""
import tomllib

import pytest

SCENE = """
name = "copy"
duration_s = 2.0
[domain]
min_m = [0.0, 0.0, 0.0]
max_m = [0.2, 0.2, 0.2]
[fluid]
solver = "wcsph"
particle_spacing_m = 0.02   # a comment the copy need not keep
[[bodies]]
name = "spoon"
mesh = "../meshes/spoon.obj"
position_m = [0.1, 0.1, 0.05]
[[devices]]
name = "hand"
start_position_m = [0.1, 0.1, 0.3]
[[devices.motion]]
kind = "oscillate"
axis = [1.0, 0.0, 0.0]
amplitude_m = 0.02
frequency_hz = 1.0
start_s = 0.5
stop_s = 1_500e-3
[[devices.motion]]
kind = "keyframes"
[[devices.motion.keyframes]]
t_s = 0.0
position_m = [0.1, 0.1, 0.3]
[[devices]]
name = "other"
start_position_m = [0.0, 0.0, 0.3]
[[devices.motion]]
kind = "hold"
"""


@pytest.fixture
def launcher():
    from hapfluid import launcher
    return launcher


def test_the_device_scene_moves_motions_by_the_lead_in_and_hands_into_their_device_frame(launcher, source_dir,
                                                                                        tmp_path):
    scenes = tmp_path / "scenes"
    scenes.mkdir()
    scene = scenes / "copy.toml"
    scene.write_text(SCENE)
    original = tomllib.loads(SCENE)
    copy = tomllib.loads(launcher.device_scene(scene, tmp_path, 2.0, {"hand": [0.1, 0.1, 0.25]}).read_text())
    hand, other = copy["devices"]
    assert [s["start_s"] for s in hand["motion"]] == [2.5, 2.0]  # a segment without start_s starts at the lead-in
    assert hand["motion"][0]["stop_s"] == pytest.approx(3.5)
    assert hand["start_position_m"] == pytest.approx([0.0, 0.0, 0.05])
    assert hand["motion"][1]["keyframes"][0]["position_m"] == pytest.approx([0.0, 0.0, 0.05])
    assert other["start_position_m"] == [0.0, 0.0, 0.3] and other["motion"][0]["start_s"] == 2.0  # no offset given
    assert copy["bodies"][0]["mesh"] == str((tmp_path / "meshes" / "spoon.obj").resolve())
    # Everything else as it was.
    for key in ("name", "duration_s", "domain", "fluid"):
        assert copy[key] == original[key]
    assert {k: v for k, v in hand["motion"][0].items() if k not in ("start_s", "stop_s")} == \
        {k: v for k, v in original["devices"][0]["motion"][0].items() if k not in ("start_s", "stop_s")}


def test_the_private_rig_gives_every_loopback_device_its_own_socket_and_keeps_the_rest(launcher, source_dir):
    text = (source_dir / "config" / "rigs" / "fake_dual.toml").read_text()
    scene = {"devices": [{"name": "left", "start_position_m": [0.1, 0.0, 0.2]},
                         {"name": "right", "start_position_m": [0.3, 0.0, 0.2]}]}
    copy_text, offsets = launcher.private_rig_text(text, scene, "t42")
    rig, copy = tomllib.loads(text), tomllib.loads(copy_text)
    assert [d["transport"]["address"] for d in copy["devices"]] == ["/tmp/hapfluid-t42-1.sock",
                                                                    "/tmp/hapfluid-t42-2.sock"]
    for a, b in zip(rig["devices"], copy["devices"]):
        a["transport"].pop("address"), b["transport"].pop("address")
        assert a == b
    assert {k: v for k, v in rig.items() if k != "devices"} == {k: v for k, v in copy.items() if k != "devices"}
    offset = rig["devices"][0].get("mapping", {}).get("offset_m", [0.0, 0.0, 0.0])
    assert offsets["left"] == pytest.approx([0.1 + offset[0], offset[1], 0.2 + offset[2]])


def test_an_emulated_arm_whose_mapping_rotates_is_refused_by_name(launcher, source_dir):
    text = (source_dir / "config" / "rigs" / "fake_single.toml").read_text().replace(
        "rotation = [1.0, 0.0, 0.0, 0.0]", "rotation = [0.0, 0.0, 0.0, 1.0]")
    with pytest.raises(SystemExit, match='rig device "hand".*no rotation'):
        launcher.private_rig_text(text, {"devices": [{"name": "hand"}]}, "t43")
