"""hapfluid.c_constants, the headers' bit flags as the build generates them (scripts/gen_c_constants.py):
what the package holds is what the headers say now, and a header the generator cannot read
stops the build naming the header and the enum."""
import re
import shutil
import subprocess
import sys

from hapfluid import c_constants


def generate(source_dir, tmp_path, headers_from=None):
    out = tmp_path / "c_constants.py"
    result = subprocess.run([sys.executable, str(source_dir / "scripts" / "gen_c_constants.py"),
                             str(headers_from or source_dir), str(out)], capture_output=True, text=True, timeout=60)
    return result, out


def test_the_package_holds_what_the_headers_say(source_dir, tmp_path):
    result, out = generate(source_dir, tmp_path)
    assert result.returncode == 0, result.stderr
    assert out.read_text() == (source_dir / "scripts" / "hapfluid" / "c_constants.py").read_text()


def test_every_flag_of_the_headers_is_there_with_its_bit(source_dir):
    # Read the headers here too, the simplest way: every "name = 1u << N" of an enum.
    flags = (source_dir / "rt_core/include/hapfluid/safety/flags.hpp").read_text()
    for prefix, cls in (("flag_", c_constants.Flag), ("fault_", c_constants.Fault)):
        pairs = re.findall(rf"\b{prefix}(\w+) = 1u << (\d+)", flags)
        assert pairs and {n: 1 << int(b) for n, b in pairs} == {m.name: m.value for m in cls}
    codec = (source_dir / "firmware_bridge/codec/include/hapfluid/wire/codec.h").read_text()
    pairs = re.findall(r"\bHF_FAULT_(\w+) = 1u << (\d+)", codec)
    assert pairs and {n: 1 << int(b) for n, b in pairs} == {m.name: m.value for m in c_constants.DeviceFault}
    assert c_constants.LoopFlag.not_preempt_rt == 1 << 3


def test_a_header_without_an_expected_enum_is_named(source_dir, tmp_path):
    copy = tmp_path / "src"
    for rel in ("rt_core/include/hapfluid/safety/flags.hpp", "rt_core/include/hapfluid/rt/rt_setup.hpp",
                "firmware_bridge/codec/include/hapfluid/wire/codec.h"):
        (copy / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(source_dir / rel, copy / rel)
    flags = copy / "rt_core/include/hapfluid/rt/rt_setup.hpp"
    flags.write_text(flags.read_text().replace("enum LoopFlag", "enum LoopBits"))
    result, out = generate(source_dir, tmp_path, headers_from=copy)
    assert result.returncode != 0 and not out.exists()
    assert "rt_core/include/hapfluid/rt/rt_setup.hpp: no enum LoopFlag" in result.stderr
    # A member whose value is not a literal the generator reads is refused too, not dropped.
    flags.write_text(flags.read_text().replace("enum LoopBits", "enum LoopFlag").replace("1u << 3", "kThree"))
    result, out = generate(source_dir, tmp_path, headers_from=copy)
    assert result.returncode != 0 and "enum LoopFlag: a member this script cannot read" in result.stderr
