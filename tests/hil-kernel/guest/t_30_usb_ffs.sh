# hil-timeout: 60
# A FunctionFS gadget on dummy_hcd (bulk IN + OUT) opened by libusb by VID:PID; unbinding the UDC
# (the cable pulled) must be reported, rebinding must recover (see probes/usb_ffs_probe.c).
set -eu
. "$HIL_GUEST/lib.sh"
probe="$HIL_BUILD/hil/bin/hil-usb-ffs-probe"
ffs_gadget hilprobe 1209 0002 /run/ffs-hilprobe
"$probe" device /run/ffs-hilprobe >device.log 2>&1 &
wait_for 20 test -e /run/ffs-hilprobe/ep2 || { cat device.log; fail "FunctionFS endpoints never appeared"; }
wait_for 10 gadget_bind hilprobe dummy_udc.0 || { cat device.log; fail "could not bind the gadget to dummy_udc.0"; }
rc=0
"$probe" host 1209 0002 /sys/kernel/config/usb_gadget/hilprobe/UDC dummy_udc.0 || rc=$?
echo "--- device side:"; cat device.log
exit $rc
