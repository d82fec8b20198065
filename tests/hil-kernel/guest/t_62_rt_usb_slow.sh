# hil-timeout: 90
# The 1 kHz loop against a slow USB bulk arm: the fake arm's FunctionFS function (dummy_hcd)
# takes one OUT packet every 20 ms, so the host's transfers wait for it. hil-loop-io-check runs
# the loop's device work (poll, send) at 1 kHz for 3 s beside cyclictest and must find, on the
# loop thread: no allocation, no lock call (libusb takes its mutexes in submit and in event
# handling), no system call but its clock; no tick longer than cyclictest's longest latency + 2
# periods, the median tick within one period; and commands reaching the device fresh. The
# device takes commands every interval (20 ms and what the emulated bus adds); the newest waits
# behind at most the transfer in flight (one interval), is taken with the next (one more), and
# its echo comes back with a state within a third: a median age of at most 3 intervals, where a
# queue of stale commands in the kernel would add an interval for each one it holds.
set -eu
. "$HIL_GUEST/lib.sh"
ffs_gadget hapfluid 1209 4846 /run/ffs-hapfluid
start_fake fake --transport usb_bulk --address /run/ffs-hapfluid --motion hold --rate-hz 250 \
    --watchdog-ms "$HIL_WATCHDOG_MS" --out-interval-ms 20
udc=/sys/kernel/config/usb_gadget/hapfluid/UDC
# The function writes its descriptors as it starts; until then binding fails with ENODEV.
wait_for 10 sh -c "echo dummy_udc.0 >$udc" || fail "binding the FunctionFS gadget to dummy_udc.0"
wait_for 30 usb_present 1209 4846 || fail "1209:4846 never enumerated"
step "slow FunctionFS gadget bound"
rc=0
"$HIL_BUILD/hil/bin/hil-loop-io-check" --transport usb_bulk --address 1209:4846 --seconds 3 --cyclictest \
    --max-command-age-transfers 3 || rc=$?
stop_pid "$FAKE_PID" "haptic-fake-device (usb_bulk, FunctionFS)"
cat fake.out
[ $rc -eq 0 ] || fail "the loop's device I/O over libusb broke the real-time rules (see above)"
pass "1 kHz loop over libusb with a device that takes a transfer every 20 ms: no allocation, lock or system call on the loop thread, ticks bounded by cyclictest, fresh commands applied"
