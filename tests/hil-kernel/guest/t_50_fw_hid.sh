# hil-timeout: 90
# The project's fake arm presents itself over USB HID through uhid with the project's report
# descriptor (1209:4846, report 1 in / 2 out / 3 feature); the host uses the hidapi driver exactly
# as on a rig. The host starts first, as a rig's services do at boot before the arm is powered:
# the driver opens 1209:4846 while no such device exists, must report it disconnected (a link
# fault, not an error) and keep being polled, and once the uhid device is created it must take it
# up by itself: states, commands applied. Then the device is unplugged (the fake device exits, its
# uhid device and /dev/hidraw node vanish): the driver must report it, and once a restarted device
# is there the same driver must recover by itself (haptic-rt opens its devices once). Last, a
# device present at open: the device watchdog. The driver is addressed as a rig addresses it, by
# VID:PID (`1209:4846`); a last short check opens it by its /dev/hidrawN node.
set -eu
. "$HIL_GUEST/lib.sh"
fake_args="--transport hid --address 1209:4846 --motion pour --watchdog-ms $HIL_WATCHDOG_MS"
# present: the arm's hidraw node exists, on the USB bus type (HID_ID 0003:00001209:00004846).
present='grep -qsx "HID_ID=0003:00001209:00004846" /sys/class/hidraw/hidraw*/device/uevent'
eval "$present" && fail "a 1209:4846 hidraw device exists before the test created one"
step "host first: no 1209:4846 device yet"
device_check --transport hid --address 1209:4846 --force-n 0.8 \
    --plug-cmd "$HIL_BIN/haptic-fake-device $fake_args >fake.out 2>&1 & echo \$! >fake.pid; until $present; do sleep 0.05; done" \
    --expect unplug \
    --unplug-cmd "kill -TERM \$(cat fake.pid); while $present; do sleep 0.05; done" \
    --replug-cmd "$HIL_BIN/haptic-fake-device $fake_args >fake2.out 2>&1 & echo \$! >fake.pid; until $present; do sleep 0.05; done" \
    --recover self \
    || { cat fake.out; check_hidapi_lists 1209 4846; fail "host driver checks over hidapi"; }
step "absent at start, unplug/replug checks done"
node=$(hidraw_of 1209 4846)
echo "uhid device: $node ($(grep -E 'HID_NAME|HID_ID' /sys/class/hidraw/${node#/dev/}/device/uevent | tr '\n' ' '))"
check_hidapi_lists 1209 4846
device_check --transport hid --address 1209:4846 --force-n 0.8 --expect watchdog \
    || { cat fake2.out; fail "watchdog over hidapi"; }
# A rig may also name the node itself (transport.address = "/dev/hidrawN"): the driver checks it
# is a hidraw node before hidapi opens it (hidapi 0.13 crashes on one that is not).
device_check --transport hid --address "$node" --states 50 --command-s 0.2 \
    || { cat fake2.out; fail "the driver addressed by its hidraw node $node"; }
stop_pid "$(cat fake.pid)" "haptic-fake-device (hid)"
cat fake.out fake2.out
pass "fake arm over uhid/hidraw <-> hidapi driver: absent at open and taken up when created, states, commands, watchdog, unplug reported, recovered after replug"
