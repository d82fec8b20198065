# hil-timeout: 90
# The udev rules the project ships (firmware_bridge/udev/70-hapfluid.rules) parse and match the
# devices as the kernel really presents them: the arm over hidraw (uhid), the arm over USB (a
# gadget on dummy_hcd), a SpaceMouse over hidraw, and give them the `hapfluid` group and mode
# 0660 so the real-time loop needs no root; an unrelated HID device must stay untouched.
# `udevadm verify` needs systemd >= 253 (Debian 12 has 252): `udevadm test` runs the rules
# engine on each device instead and shows what it would apply.
set -eu
. "$HIL_GUEST/lib.sh"
rules="$HIL_SRC/firmware_bridge/udev/70-hapfluid.rules"
[ -f "$rules" ] || fail "the project ships no udev rules at $rules"
# the group only: uaccess would hand a force-producing arm to whoever sits at the seat
! grep -v '^#' "$rules" | grep -qi uaccess || fail "70-hapfluid.rules tags a device uaccess"
mkdir -p /run/udev/rules.d
cp "$rules" /run/udev/rules.d/
# The group the rules name must resolve, as after `make install` on a rig: a guest-only
# /etc/group with it (the host root is read-only; this bind mount lives in the guest).
cp /etc/group /tmp/group
grep -q '^hapfluid:' /tmp/group || echo 'hapfluid:x:977:' >>/tmp/group
mount --bind /tmp/group /etc/group

# Only presence matters here (no driver talks to them): 50 Hz keeps four fake devices from
# saturating the one emulated CPU.
start_fake arm --transport hid --address 1209:4846 --motion hold --rate-hz 50
arm_pid=$FAKE_PID
start_fake sm --transport hid --kind spacemouse --motion hold --rate-hz 50
sm_pid=$FAKE_PID
ffs_gadget hapfluid 1209 4846 /run/ffs-hapfluid
start_fake usb --transport usb_bulk --address /run/ffs-hapfluid --motion hold --rate-hz 50
wait_for 10 gadget_bind hapfluid dummy_udc.0 || fail "could not bind the gadget"
start_fake other --transport hid --address 1209:0001 --motion hold --rate-hz 50   # an unrelated HID device
other_pid=$FAKE_PID
wait_for 20 hidraw_of 1209 4846 >/dev/null || fail "no hidraw node for the arm"
wait_for 20 hidraw_of 256F C635 >/dev/null || fail "no hidraw node for the SpaceMouse"
wait_for 20 usb_present 1209 4846 || fail "the USB arm never enumerated"

# expect_rule SYSPATH WHAT yes|no: udevadm test on SYSPATH applies (or not) the project's rules.
expect_rule() {
    local out
    out=$(udevadm test "$1" 2>&1) || { echo "$out" | tail -n 20; fail "udevadm test $1 failed"; }
    # The rules file is parsed at every run: it must be read, with no complaint about any line.
    echo "$out" | grep -q "Reading rules file: /run/udev/rules.d/70-hapfluid.rules" || fail "udevadm did not read the rules"
    if echo "$out" | grep "70-hapfluid" | grep -iE "invalid|unknown|ignoring|error"; then
        fail "udevadm reports problems in 70-hapfluid.rules"
    fi
    echo "$out" | grep -E "70-hapfluid.rules:[0-9]" | sed "s|^|  $2: |" || true
    if [ "$3" = yes ]; then
        echo "$out" | grep -q "70-hapfluid.rules:[0-9]" || fail "$2: the project's rules do not match $1"
        echo "$out" | grep -qE "MODE.*0660" || fail "$2: no MODE 0660 from the rules"
        echo "$out" | grep -qE "GROUP 977|GROUP.*hapfluid" || fail "$2: group hapfluid not applied"
    else
        ! echo "$out" | grep -q "70-hapfluid.rules:[0-9]" || fail "$2: the project's rules match an unrelated device $1"
    fi
    echo "$2: rules $([ "$3" = yes ] && echo applied || echo not applied, as expected)"
}
arm_node=$(hidraw_of 1209 4846)
expect_rule "/sys/class/hidraw/${arm_node#/dev/}" "arm over hidraw ($arm_node)" yes
sm_node=$(hidraw_of 256F C635)
expect_rule "/sys/class/hidraw/${sm_node#/dev/}" "SpaceMouse over hidraw ($sm_node)" yes
for d in /sys/bus/usb/devices/*; do
    [ "$(cat $d/idVendor 2>/dev/null):$(cat $d/idProduct 2>/dev/null)" = 1209:4846 ] && usb_dev=$d
done
expect_rule "$usb_dev" "arm over USB (${usb_dev##*/})" yes
wait_for 20 hidraw_of 1209 0001 >/dev/null || fail "no hidraw node for the unrelated 1209:0001"
other=$(hidraw_of 1209 0001)
expect_rule "/sys/class/hidraw/${other#/dev/}" "unrelated HID 1209:0001 ($other)" no
stop_pid "$other_pid" "haptic-fake-device (hid)"
stop_pid "$arm_pid" "haptic-fake-device (hid)"
stop_pid "$sm_pid" "haptic-fake-device (spacemouse)"
# (the usb_bulk fake device is left to the runner: it ignores SIGTERM, see 60_fw_usb)
umount /etc/group
pass "70-hapfluid.rules parse and give group hapfluid, mode 0660 to the arm (hidraw, USB) and the SpaceMouse only"
