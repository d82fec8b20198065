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
# gadget NAME VID PID FUNCTION: a configfs gadget with one configuration holding one function
# (e.g. ffs.NAME, hid.NAME), created and linked; the caller sets the function up.
gadget() {
    local g=/sys/kernel/config/usb_gadget/$1
    mkdir -p "$g" || fail "configfs gadget $g"
    echo "0x$2" >"$g/idVendor"; echo "0x$3" >"$g/idProduct"
    echo 0x0200 >"$g/bcdUSB"; echo 0x0100 >"$g/bcdDevice"
    mkdir -p "$g/strings/0x409" "$g/configs/c.1/strings/0x409" "$g/functions/$4" || fail "gadget function $4"
    echo "hapfluid" >"$g/strings/0x409/manufacturer"
    echo "$1" >"$g/strings/0x409/product"
    echo "HIL-$1" >"$g/strings/0x409/serialnumber"
    echo "$1 config" >"$g/configs/c.1/strings/0x409/configuration"
    echo 100 >"$g/configs/c.1/MaxPower"
}
gadget_link() { ln -s "/sys/kernel/config/usb_gadget/$1/functions/$2" "/sys/kernel/config/usb_gadget/$1/configs/c.1/" 2>/dev/null || true; }
# ffs_gadget NAME VID PID MOUNT: a configfs gadget with one FunctionFS function, its ep0 mounted
# at MOUNT. The caller starts the function's process on MOUNT, then binds with gadget_bind.
ffs_gadget() {
    gadget "$1" "$2" "$3" "ffs.$1"
    gadget_link "$1" "ffs.$1"
    mkdir -p "$4"
    mount -t functionfs "$1" "$4" || fail "mount -t functionfs $1 $4"
}
# hid_gadget NAME VID PID: a configfs gadget with one HID function (usb_f_hid) presenting the
# arm's report descriptor with 64-byte reports, as the real arm does over USB. Bind it with
# gadget_bind: the host's usbhid then gives it a hidraw node, and the function's /dev/hidgN
# (the only one: tests run one gadget at a time) is the device side for haptic-fake-device.
hid_gadget() {
    local f=/sys/kernel/config/usb_gadget/$1/functions/hid.$1 hex
    gadget "$1" "$2" "$3" "hid.$1"
    echo 0 >"$f/protocol"; echo 0 >"$f/subclass"; echo 64 >"$f/report_length"
    hex=$("$HIL_BIN/haptic-fake-device" --hid-report-descriptor haptic_arm) || fail "no report descriptor"
    printf '%b' "$(echo "$hex" | sed 's/../\\x&/g')" >"$f/report_desc" || fail "writing $f/report_desc"
    gadget_link "$1" "hid.$1"
}
# gadget_bind NAME UDC: plugs the gadget into the virtual bus (after its function wrote its
# descriptors: before that the bind fails with ENODEV).
gadget_bind() { echo "$2" >"/sys/kernel/config/usb_gadget/$1/UDC"; }
# start_fake NAME ARGS...: haptic-fake-device in the background, output in NAME.out; waits until
# it says it is ready. Its pid is in $FAKE_PID.
start_fake() {
    local name=$1; shift
    "$HIL_BIN/haptic-fake-device" "$@" >"$name.out" 2>&1 &
    FAKE_PID=$!
    wait_for 30 grep -q "ready on" "$name.out" || { cat "$name.out"; fail "haptic-fake-device ($name) never became ready"; }
    echo "fake device: $(grep -m1 'ready on' "$name.out")"
}
# stop_pid PID [WHAT]: SIGTERM and wait (the fake device writes its summary and log on the way
# out). A process that has not exited 10 s after SIGTERM fails the test: a rig's supervisor must
# be able to stop the device firmware (and haptic-rt) at any time, whatever the host is doing.
stop_pid() {
    kill -TERM "$1" 2>/dev/null || return 0
    local i
    for i in $(seq 200); do kill -0 "$1" 2>/dev/null || { wait "$1" 2>/dev/null || true; return 0; }; sleep 0.05; done
    kill -KILL "$1" 2>/dev/null
    wait "$1" 2>/dev/null || true
    fail "${2:-process $1} did not exit within 10 s of SIGTERM and was killed"
}
# step MSG: a progress line with the guest's uptime (seconds; only to see where time goes).
step() { echo "[$(cut -d' ' -f1 /proc/uptime) s] $*"; }
# hidraw_of VID PID: the /dev/hidrawN node of the HID device VID:PID (upper-case hex), if any.
hidraw_of() {
    local d
    for d in /sys/class/hidraw/hidraw*; do
        case "$(readlink -f "$d/device")" in *":$1:$2."*) echo "/dev/${d##*/}"; return 0 ;; esac
    done
    return 1
}
# usb_present VID PID: a USB device VID:PID (lower-case hex) is enumerated on the host side.
usb_present() {
    local d
    for d in /sys/bus/usb/devices/*; do
        [ "$(cat "$d/idVendor" 2>/dev/null):$(cat "$d/idProduct" 2>/dev/null)" = "$1:$2" ] && return 0
    done
    return 1
}
# The fake device's command watchdog in these tests. The emulated CPU stalls now and then for
# tens of ms (TCG), which would trip a rig's 20 ms watchdog on a healthy link; 250 ms still
# proves the function (silence -> motors off, fault reported) without flaking on emulation.
HIL_WATCHDOG_MS=250
# device_check ARGS...: runs hil-device-check; fails the test unless it passed, including its
# final close (a driver that crashes when the loop shuts down takes haptic-rt with it). Its rig
# device declares the fake devices' HIL_WATCHDOG_MS: open refuses a device whose INFO reply
# reports a longer watchdog than the rig assumes.
device_check() {
    local rc=0
    "$HIL_BUILD/hil/bin/hil-device-check" --device-watchdog-ms "$HIL_WATCHDOG_MS" "$@" >check.out 2>&1 || rc=$?
    cat check.out
    [ $rc -eq 0 ] || { echo "hil-device-check exited with status $rc"; return 1; }
    grep -q "^PHASE close" check.out || { echo "hil-device-check did not close the device"; return 1; }
}
# hidapi_lists VID PID: hidapi (hidraw backend, as the driver uses it) enumerates VID:PID.
hidapi_lists() {
    "$HIL_PY" - "$1" "$2" <<'PY'
import ctypes, ctypes.util, sys
lib = ctypes.CDLL("libhidapi-hidraw.so.0")
class Info(ctypes.Structure):
    pass
Info._fields_ = [("path", ctypes.c_char_p), ("vendor_id", ctypes.c_ushort), ("product_id", ctypes.c_ushort)]
lib.hid_enumerate.restype = ctypes.POINTER(Info)
lib.hid_init()
found = lib.hid_enumerate(int(sys.argv[1], 16), int(sys.argv[2], 16))
print("hidapi enumerates", sys.argv[1] + ":" + sys.argv[2], "at", found.contents.path.decode() if found else "nothing")
sys.exit(0 if found else 1)
PY
}
# check_hidapi_lists VID PID: a rig names the device by VID:PID, so hidapi must list it; the fake
# device presents it on the USB bus type (HID_ID 0003:...) like the real hardware. (On
# BUS_VIRTUAL, 0x06, Debian 12's hidapi 0.13 would not list it and a rig address finds nothing.)
check_hidapi_lists() {
    local node
    node=$(hidraw_of "$(echo "$1" | tr a-f A-F)" "$(echo "$2" | tr a-f A-F)") || fail "no hidraw node for $1:$2"
    grep -q "^HID_ID=0003:" "/sys/class/hidraw/${node#/dev/}/device/uevent" ||
        fail "$1:$2 ($node) is not on the USB bus type: $(grep HID_ID "/sys/class/hidraw/${node#/dev/}/device/uevent")"
    hidapi_lists "$1" "$2" || fail "hidapi does not list $1:$2, so a rig address '$1:$2' cannot open it"
}
# candump_sample LOG: the first and last 10 frames of every CAN ID in a candump -L log. cantools
# decodes ~300 frames/s under TCG, so the DBC is checked on every message kind seen on the bus
# (first and last: before and after the commands changed) rather than on every frame.
candump_sample() {
    awk '{ split($3, a, "#"); id = a[1]; n[id]++
           if (n[id] <= 10) print; else last[id, n[id] % 10] = $0 }
         END { for (k in last) print last[k] }' "$1"
}
# cantools_decode DBC <LOG: `cantools decode --single-line DBC`, the same CLI entry point, with
# matplotlib (imported only by cantools' `plot` subcommand) kept out: under TCG that import alone
# costs ~20 s, and decoding needs none of it.
cantools_decode() {
    "$HIL_PY" -c "import sys; sys.modules['matplotlib'] = None; import cantools; sys.argv[0] = 'cantools'; sys.exit(cantools._main())" \
        decode --single-line "$1"
}
