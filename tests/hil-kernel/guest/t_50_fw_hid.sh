# hil-timeout: 90
# The project's fake arm presents itself over USB HID through uhid with the project's report
# descriptor (1209:4846, report 1 in / 2 out / 3 feature); the host uses the hidapi driver exactly
# as on a rig: states, commands applied, the device watchdog. Then the device is unplugged (the
# fake device exits, its uhid device and /dev/hidraw node vanish): the driver must report it;
# a restarted device must be reopened by VID:PID.
set -eu
. "$HIL_GUEST/lib.sh"
fake_args="--transport hid --address 1209:4846 --motion pour --watchdog-ms $HIL_WATCHDOG_MS"
start_fake fake $fake_args
echo $FAKE_PID >fake.pid
wait_for 20 hidraw_of 1209 4846 >/dev/null || { cat fake.out; fail "no /dev/hidraw node for 1209:4846"; }
node=$(hidraw_of 1209 4846)
echo "uhid device: $node ($(grep -E 'HID_NAME|HID_ID' /sys/class/hidraw/${node#/dev/}/device/uevent | tr '\n' ' '))"
step "device presented"
check_hidapi_lists 1209 4846 "the arm"
# The hidraw node is the address the driver opens (a rig may give either form); a replugged
# device may get another node, so replug waits for the new one and the reopen uses it.
device_check --transport hid --address "$node" --force-n 0.8 --expect unplug \
    --unplug-cmd "kill -TERM \$(cat fake.pid); while [ -e $node ]; do sleep 0.05; done" \
    --replug-cmd "$HIL_BIN/haptic-fake-device $fake_args >fake2.out 2>&1 & echo \$! >fake.pid; while [ ! -e $node ]; do sleep 0.05; done" \
    || { cat fake.out; fail "host driver checks over hidapi"; }
step "unplug/replug checks done"
device_check --transport hid --address "$(hidraw_of 1209 4846)" --force-n 0.8 --expect watchdog \
    || { cat fake2.out; fail "watchdog over hidapi"; }
stop_pid "$(cat fake.pid)" "haptic-fake-device (hid)"
cat fake.out fake2.out
pass "fake arm over uhid/hidraw <-> hidapi driver: states, commands, watchdog, unplug reported, replug reopened"
