# hil-timeout: 90
# The 1 kHz loop against a slow USB HID arm, on the rig's own path: the fake arm is a USB gadget
# with a HID function (usb_f_hid on dummy_hcd), so the host has usbhid, a hidraw node and
# hidapi, and every hid_write is an interrupt OUT transfer that waits until the device takes it
# (with uhid it would only be queued). The device takes the reports its endpoint buffered only
# every 20 ms. hil-loop-io-check runs the loop's device work (poll, send) at 1 kHz for 3 s beside
# cyclictest and must find, on the loop thread: no allocation, no lock call, no system call but
# its clock; no tick longer than cyclictest's longest latency + 2 periods, the median tick
# within one period; and commands reaching the device fresh. The device takes commands every
# interval (20 ms and what the emulated bus adds); the newest waits behind at most the transfer
# in flight (one interval), is taken with the next (one more), and its echo comes back with a
# state within a third: a median age of at most 3 intervals, where a queue of stale commands
# would add an interval for each one it holds.
set -eu
. "$HIL_GUEST/lib.sh"
hid_gadget hidarm 1209 4846
gadget_bind hidarm dummy_udc.0 || fail "binding the HID gadget to dummy_udc.0"
wait_for 30 hidraw_of 1209 4846 >/dev/null || fail "usbhid gave the HID gadget no hidraw node"
node=$(hidraw_of 1209 4846)
echo "host side: $node ($(grep -E 'HID_ID|HID_NAME' /sys/class/hidraw/${node#/dev/}/device/uevent | tr '\n' ' '))"
grep -q "^DRIVER=hid-generic" /sys/class/hidraw/${node#/dev/}/device/uevent || fail "$node is not a hid-generic device"
check_hidapi_lists 1209 4846
hidg=$(ls /dev/hidg* 2>/dev/null | head -n 1)
[ -c "$hidg" ] || fail "the HID function has no /dev/hidgN node"
start_fake fake --transport hid --address "$hidg" --motion hold --rate-hz 250 --watchdog-ms "$HIL_WATCHDOG_MS" \
    --out-interval-ms 20
step "slow HID gadget up on $hidg"
rc=0
"$HIL_BUILD/hil/bin/hil-loop-io-check" --transport hid --address 1209:4846 --seconds 3 --cyclictest \
    --max-command-age-transfers 3 || rc=$?
stop_pid "$FAKE_PID" "haptic-fake-device (gadget hid)"
cat fake.out
[ $rc -eq 0 ] || fail "the loop's device I/O over hidapi broke the real-time rules (see above)"
pass "1 kHz loop over hidapi/usbhid with a device that takes reports every 20 ms: no allocation, lock or system call on the loop thread, ticks bounded by cyclictest, fresh commands applied"
