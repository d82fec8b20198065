# hil-timeout: 90
# The project's fake arm as a USB bulk device: a configfs gadget 1209:4846 whose FunctionFS
# function the fake device drives (one vendor interface, bulk IN + OUT) on dummy_hcd; the host's
# libusb driver finds it by VID:PID, streams states and sends commands. Unbinding the UDC (the
# cable pulled) must be reported as disconnected; after rebinding the driver must reopen it.
set -eu
. "$HIL_GUEST/lib.sh"
ffs_gadget hapfluid 1209 4846 /run/ffs-hapfluid
start_fake fake --transport usb_bulk --address /run/ffs-hapfluid --motion tilt --watchdog-ms "$HIL_WATCHDOG_MS"
wait_for 10 gadget_bind hapfluid dummy_udc.0 || { cat fake.out; fail "could not bind the gadget to dummy_udc.0"; }
wait_for 20 usb_present 1209 4846 || fail "the gadget never enumerated on the dummy_hcd bus"
for d in /sys/bus/usb/devices/*; do
    [ "$(cat $d/idProduct 2>/dev/null)" = 4846 ] || continue
    echo "enumerated: ${d##*/} $(cat $d/idVendor):$(cat $d/idProduct) \"$(cat $d/product)\" speed $(cat $d/speed) Mbit/s"
    for e in $d/${d##*/}:1.0/ep_*; do
        echo "  interface 0 endpoint $(cat $e/bEndpointAddress) $(cat $e/type) max packet $(cat $e/wMaxPacketSize)"
    done
done
step "gadget bound"
udc=/sys/kernel/config/usb_gadget/hapfluid/UDC
device_check --transport usb_bulk --address 1209:4846 --force-n 1.2 --expect unplug \
    --unplug-cmd "echo '' > $udc" --replug-cmd "echo dummy_udc.0 > $udc" \
    || { cat fake.out; fail "host driver checks over libusb"; }
step "unplug/replug checks done"
device_check --transport usb_bulk --address 1209:4846 --expect watchdog \
    || { cat fake.out; fail "watchdog over libusb"; }
stop_pid "$FAKE_PID" "haptic-fake-device (usb_bulk, FunctionFS)"
cat fake.out
pass "fake arm as a FunctionFS gadget <-> libusb driver: states, commands, watchdog, unplug reported, replug reopened"
