"""haptic-config check: the command a rig operator runs before starting anything. Every shipped
file validates; each class of broken file is rejected with a message naming file, line, key,
value and reason, and a non-zero exit code."""
import pathlib
import subprocess
import sys

import pytest


def check(binary, *files):
    return subprocess.run([str(binary("haptic-config")), "check", *map(str, files)],
                          capture_output=True, text=True, timeout=60)


def test_every_shipped_rig_and_scene_validates(binary, source_dir):
    files = sorted((source_dir / "config" / "rigs").glob("*.toml")) + sorted((source_dir / "config" / "scenes").glob("*.toml"))
    assert len(files) >= 14
    result = check(binary, *files)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count(": ok (") == len(files)


def test_scenes_cross_checked_against_a_rig(binary, source_dir, tmp_path):
    scene = tmp_path / "live.toml"
    text = (source_dir / "config" / "scenes" / "spoon_stirring.toml").read_text()
    text = text.replace('mesh = "../meshes/', f'mesh = "{source_dir}/config/meshes/')
    text = text.replace('source = "scripted"', 'source = "rig"\nrig_device = "thumb"')
    scene.write_text(text)
    result = check(binary, "--rig", source_dir / "config" / "rigs" / "fake_single.toml", scene)
    assert result.returncode == 1
    assert 'devices.hand.rig_device = "thumb": no device with that name in rig' in result.stderr


BROKEN_RIGS = {
    "negative limit": ('[[devices]]\nname = "left"\ntransport = { kind = "loopback", address = "/tmp/a" }\nmax_force_n = -3\n',
                       'rig.toml:4: devices.left.max_force_n = -3: must be > 0'),
    "unknown key": ('[rt]\nprioirty = 50\n[[devices]]\nname = "a"\ntransport = { kind = "loopback", address = "/tmp/a" }\n',
                    'rig.toml:2: rt.prioirty = 50: unknown key'),
    "wrong type": ('[[devices]]\nname = "a"\ntransport = { kind = "loopback", address = "/tmp/a" }\nsim_stale_ms = "fast"\n',
                   'devices.a.sim_stale_ms = "fast": must be a number'),
    "missing field": ('[[devices]]\nname = "a"\n', 'devices.a.transport: missing'),
    "syntax": ('[[devices]\n', 'rig.toml:1: TOML syntax error'),
}


@pytest.mark.parametrize("case", sorted(BROKEN_RIGS))
def test_broken_rig_is_rejected_with_a_precise_message(binary, tmp_path, case):
    text, expected = BROKEN_RIGS[case]
    path = tmp_path / "rig.toml"
    path.write_text(text)
    result = check(binary, path)
    assert result.returncode == 1
    assert expected in result.stderr, result.stderr
    assert "1 of 1 files have errors" in result.stderr


def scene_with(source_dir, tmp_path, old, new):
    """The frozen stirring scene with one edit, written where its relative mesh path still resolves."""
    path = source_dir / "tests" / "config" / "scenes" / "stirring_base.toml"
    text = path.read_text()
    assert old in text
    out = tmp_path / "scenes" / "broken.toml"
    out.parent.mkdir(exist_ok=True)
    (tmp_path / "meshes").mkdir(exist_ok=True)
    for mesh in (source_dir / "config" / "meshes").glob("*.obj"):
        (tmp_path / "meshes" / mesh.name).write_bytes(mesh.read_bytes())
    out.write_text(text.replace(old, new, 1))
    return out


BROKEN_SCENES = {
    "non-positive spacing": ("particle_spacing_m = 0.02", "particle_spacing_m = 0.0",
                             "fluid.particle_spacing_m = 0.0: must be > 0"),
    "body outside the domain": ("position_m = [0.20, 0.15, 0.075]", "position_m = [0.20, 0.15, 0.30]",
                                "bodies.spoon.position_m = [0.2, 0.15, 0.3]: body outside the domain"),
    "mesh not found": ('mesh = "../meshes/spoon.obj"', 'mesh = "../meshes/ladle.obj"',
                       'bodies.spoon.mesh = "../meshes/ladle.obj": mesh file not found'),
    "coupling to a missing device": ('device = "hand"\nbody', 'device = "foot"\nbody',
                                     'couplings[0].device = "foot": coupling to a missing device "foot"'),
    "coupling to a missing body": ('body = "spoon"', 'body = "ladle"',
                                   'couplings[0].body = "ladle": coupling to a missing body "ladle"'),
    "non-finite": ("viscosity_pa_s = 2.0", "viscosity_pa_s = inf", "fluid.viscosity_pa_s = inf: must be finite"),
    "unknown key": ("look = \"water\"", "colour = \"water\"", 'fluid.colour = "water": unknown key'),
}


@pytest.mark.parametrize("case", sorted(BROKEN_SCENES))
def test_broken_scene_is_rejected_with_a_precise_message(binary, source_dir, tmp_path, case):
    old, new, expected = BROKEN_SCENES[case]
    result = check(binary, scene_with(source_dir, tmp_path, old, new))
    assert result.returncode == 1
    assert "broken.toml:" in result.stderr
    assert expected in result.stderr, result.stderr


def test_shipped_meshes_are_exactly_what_the_generator_makes(source_dir, tmp_path):
    subprocess.run([sys.executable, str(source_dir / "scripts" / "gen_meshes.py"), str(tmp_path)],
                   check=True, capture_output=True, timeout=120)
    for generated in tmp_path.glob("*.obj"):
        shipped = source_dir / "config" / "meshes" / generated.name
        assert shipped.read_text() == generated.read_text(), f"{shipped} is stale: run scripts/gen_meshes.py"
