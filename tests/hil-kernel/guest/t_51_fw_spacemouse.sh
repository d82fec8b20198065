# hil-timeout: 60
# The fake device's SpaceMouse mode presents a 3Dconnexion-format uhid device (256f:c635,
# kSpaceMouseHidDescriptor); the project's SpaceMouse driver reads it through hidapi and the
# integrated pose must follow the scripted hand.
set -eu
. "$HIL_GUEST/lib.sh"
start_fake fake --transport hid --kind spacemouse --motion stir
wait_for 20 hidraw_of 256F C635 >/dev/null || { cat fake.out; fail "no /dev/hidraw node for 256f:c635"; }
echo "uhid SpaceMouse: $(hidraw_of 256F C635)"
check_hidapi_lists 256f c635 "the SpaceMouse"
device_check --transport hid --address "$(hidraw_of 256F C635)" --kind spacemouse \
    || { cat fake.out; fail "SpaceMouse driver over hidapi"; }
stop_pid "$FAKE_PID" "haptic-fake-device (spacemouse)"
pass "SpaceMouse-format uhid device -> hidapi -> SpaceMouse driver: pose follows the hand"
