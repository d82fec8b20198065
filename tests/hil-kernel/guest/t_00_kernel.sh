# hil-timeout: 20
# The guest runs Debian's kernel of the requested flavour, with every facility the suite needs:
# a test that passes on the wrong kernel (or without CAN/uhid/gadget support) would prove nothing.
set -eu
. "$HIL_GUEST/lib.sh"
echo "kernel: $(uname -r) ($(uname -v))"
case "$HIL_FLAVOUR" in
  rt) [ "$(cat /sys/kernel/realtime 2>/dev/null)" = 1 ] || fail "KERNEL=rt but /sys/kernel/realtime is not 1"
      uname -v | grep -q PREEMPT_RT || fail "KERNEL=rt but uname -v has no PREEMPT_RT" ;;
  *)  [ ! -e /sys/kernel/realtime ] || fail "default flavour booted a realtime kernel" ;;
esac
for m in vcan can_raw can_bcm uhid hid_generic dummy_hcd libcomposite usb_f_fs; do
    grep -q "^$m " /proc/modules || fail "module $m is not loaded"
done
[ -c /dev/uhid ] || fail "/dev/uhid missing"
ls /sys/class/udc/ | grep -q dummy_udc.0 || fail "no dummy_udc.0 in /sys/class/udc"
[ "$(ls /sys/class/udc | wc -l)" -eq 2 ] || fail "dummy_hcd num=2 should give two UDCs"
[ -x "$HIL_PY" ] || fail "project venv python $HIL_PY is missing (run scripts/install-deps.sh)"
echo "UDCs: $(ls /sys/class/udc | tr '\n' ' ')"
pass "kernel $(uname -r) with vcan, CAN_RAW, uhid, hidraw, dummy_hcd, FunctionFS"
