"""The shipped udev rules give the hapfluid devices to the `hapfluid` group, mode 0660, and to
nobody else: no `uaccess` tag, which would hand a force-producing arm to whoever sits at the
desktop seat (and past haptic-rt's safety layer). The HIL suite (t_70) checks that they match."""
import re

from proto_path import SOURCE_DIR

RULES = SOURCE_DIR / "firmware_bridge" / "udev" / "70-hapfluid.rules"


def rules():
    lines = [line.strip() for line in RULES.read_text().splitlines()]
    return [line for line in lines if line and not line.startswith("#")]


def test_every_rule_gives_the_hapfluid_group_read_write_and_nothing_wider():
    assert len(rules()) >= 4  # arm over hidraw and USB, two SpaceMouse families
    for rule in rules():
        assert 'GROUP="hapfluid"' in rule, rule
        assert 'MODE="0660"' in rule, rule


def test_no_rule_hands_a_device_to_the_seat_user():
    for rule in rules():
        assert not re.search(r"uaccess|seat", rule, re.IGNORECASE), rule
        assert "OWNER" not in rule, rule
