# hil-timeout: 90
# The project's fake arm as a USB bulk device: a configfs gadget 1209:4846 whose FunctionFS
# function the fake device drives (one vendor interface, bulk IN + OUT) on dummy_hcd; the host's
# libusb driver finds it by VID:PID, streams states and sends commands. The host starts first, as
# a rig's services do at boot before the arm is powered: the gadget is not bound to its UDC when
# the driver opens 1209:4846, which must report it disconnected (a link fault, not an error) and
# keep being polled; binding it (the cable plugged in) must be taken up by the same driver.
# Unbinding the UDC (the cable pulled) must be reported as disconnected; after rebinding the same
# driver must recover by itself (haptic-rt opens its devices once). Every close of a streaming
# driver must be clean, and the fake device must stop on SIGTERM although the host stopped reading
# its IN endpoint.
set -eu
. "$HIL_GUEST/lib.sh"
ffs_gadget hapfluid 1209 4846 /run/ffs-hapfluid
start_fake fake --transport usb_bulk --address /run/ffs-hapfluid --motion tilt --watchdog-ms "$HIL_WATCHDOG_MS"
usb_present 1209 4846 && fail "1209:4846 is on the bus before its gadget was bound"
step "host first: gadget not bound"
udc=/sys/kernel/config/usb_gadget/hapfluid/UDC
# The function writes its descriptors as it starts; until then binding fails with ENODEV.
bind="for i in \$(seq 200); do echo dummy_udc.0 2>/dev/null >$udc && exit 0; sleep 0.05; done; exit 1"
device_check --transport usb_bulk --address 1209:4846 --force-n 1.2 --plug-cmd "$bind" --expect unplug \
    --unplug-cmd "echo '' > $udc" --replug-cmd "echo dummy_udc.0 > $udc" --recover self \
    || { cat fake.out; fail "host driver checks over libusb"; }
step "absent at start, unplug/replug checks done"
for d in /sys/bus/usb/devices/*; do
    [ "$(cat $d/idProduct 2>/dev/null)" = 4846 ] || continue
    echo "enumerated: ${d##*/} $(cat $d/idVendor):$(cat $d/idProduct) \"$(cat $d/product)\" speed $(cat $d/speed) Mbit/s"
    for e in $d/${d##*/}:1.0/ep_*; do
        echo "  interface 0 endpoint $(cat $e/bEndpointAddress) $(cat $e/type) max packet $(cat $e/wMaxPacketSize)"
    done
done
device_check --transport usb_bulk --address 1209:4846 --expect watchdog \
    || { cat fake.out; fail "watchdog over libusb"; }
stop_pid "$FAKE_PID" "haptic-fake-device (usb_bulk, FunctionFS)"
cat fake.out
pass "fake arm as a FunctionFS gadget <-> libusb driver: absent at open and taken up when bound, states, commands, watchdog, unplug reported, recovered after replug, clean close and stop"
