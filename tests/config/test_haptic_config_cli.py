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


def test_kind_comes_from_the_schema_not_from_the_text(binary, tmp_path):
    # A comment or a string that mentions [fluid] does not make a rig a scene.
    rig = tmp_path / "rig.toml"
    rig.write_text('# copied from a scene: [fluid]\n[rt]\nperiod_ns = 1_000_000\n[[devices]]\nname = "a"\n'
                   'transport = { kind = "loopback", address = "/tmp/a" }\n')
    result = check(binary, rig)
    assert result.returncode == 0 and 'ok (rig "rig"' in result.stdout, result.stderr


def test_a_file_with_keys_of_both_schemas_is_refused_naming_them(binary, tmp_path):
    mixed = tmp_path / "mixed.toml"
    mixed.write_text('[rt]\nperiod_ns = 1_000_000\n[domain]\nmin_m = [0, 0, 0]\nmax_m = [1, 1, 1]\n')
    result = check(binary, mixed)
    assert result.returncode == 1
    assert "mixed.toml: has keys of both a rig (rt) and a scene (domain)" in result.stderr
    assert "--kind" in result.stderr


def test_kind_can_be_given(binary, tmp_path, source_dir):
    # Read as a scene, a rig has no [domain] or [fluid]: the scene schema's own messages.
    rig = source_dir / "config/rigs/fake_single.toml"
    result = subprocess.run([str(binary("haptic-config")), "check", "--kind", "scene", str(rig)],
                            capture_output=True, text=True)
    assert result.returncode == 1 and "fake_single.toml:1: domain: missing" in result.stderr, result.stderr
    result = subprocess.run([str(binary("haptic-config")), "check", "--kind", "rig", str(rig)],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("args, named", [(["check", "--bogus", "x"], "--bogus"), (["check", "--kind", "fish", "x"], "--kind"),
                                          ([], "subcommand"), (["check"], "no FILE")])
def test_usage_errors_exit_2_with_one_line_naming_the_option(binary, args, named):
    result = subprocess.run([str(binary("haptic-config")), *args], capture_output=True, text=True)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0] and lines[0].startswith("haptic-config: "), result.stderr

