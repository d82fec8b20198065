# Helpers for guest test scripts (sourced). Tests print what they check; `fail` exits non-zero
# with a line the runner reports as the failure message.
fail() { echo "FAIL: $*"; exit 1; }
pass() { echo "PASS: $*"; }
# wait_for SECONDS CMD...: polls CMD every 50 ms until it succeeds; fails after SECONDS (guest
# time under TCG is slow, so limits are generous and only catch things that never happen).
wait_for() {
    local limit=$1; shift
    local end=$(( $(date +%s) + limit ))
    until "$@" 2>/dev/null; do
        [ "$(date +%s)" -lt "$end" ] || return 1
        sleep 0.05
    done
}
# can_listening IFACE: some CAN_RAW socket has a receive filter on IFACE (candump is bound and
# will see the next frame), read from the kernel's receive lists.
can_listening() { grep -qE "^ +$1 " /proc/net/can/rcvlist_all /proc/net/can/rcvlist_fil 2>/dev/null; }
# vcan_up NAME MTU: a virtual CAN bus; MTU 16 = classic CAN only, 72 = CAN FD capable.
vcan_up() {
    ip link show "$1" >/dev/null 2>&1 || ip link add dev "$1" type vcan || fail "ip link add $1 type vcan"
    ip link set "$1" mtu "$2" || fail "ip link set $1 mtu $2"
    ip link set "$1" up || fail "ip link set $1 up"
}
# ffs_gadget NAME VID PID MOUNT: a configfs gadget with one FunctionFS function, its ep0 mounted
# at MOUNT. The caller starts the function's process on MOUNT, then binds with gadget_bind.
ffs_gadget() {
    local g=/sys/kernel/config/usb_gadget/$1
    mkdir -p "$g" || fail "configfs gadget $g"
    echo "0x$2" >"$g/idVendor"; echo "0x$3" >"$g/idProduct"
    echo 0x0200 >"$g/bcdUSB"; echo 0x0100 >"$g/bcdDevice"
    mkdir -p "$g/strings/0x409" "$g/configs/c.1/strings/0x409" "$g/functions/ffs.$1"
    echo "hapfluid" >"$g/strings/0x409/manufacturer"
    echo "$1" >"$g/strings/0x409/product"
    echo "HIL-$1" >"$g/strings/0x409/serialnumber"
    echo "$1 config" >"$g/configs/c.1/strings/0x409/configuration"
    echo 100 >"$g/configs/c.1/MaxPower"
    ln -s "$g/functions/ffs.$1" "$g/configs/c.1/" 2>/dev/null || true
    mkdir -p "$4"
    mount -t functionfs "$1" "$4" || fail "mount -t functionfs $1 $4"
}
# gadget_bind NAME UDC: plugs the gadget into the virtual bus (after its function wrote its
# descriptors: before that the bind fails with ENODEV).
gadget_bind() { echo "$2" >"/sys/kernel/config/usb_gadget/$1/UDC"; }
