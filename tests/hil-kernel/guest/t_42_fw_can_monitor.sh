# hil-timeout: 120
# hapfluid.can_monitor on python-can's socketcan interface decodes the live traffic between the
# project's fake arm (node 3, classic CAN) and the project's own driver harness haptic-device-probe
# (INFO handshake, enable + force commands): the tooling a rig engineer debugs the bus with must
# agree with the C codec on a real kernel bus.
set -eu
. "$HIL_GUEST/lib.sh"
vcan_up vcan0 16
# Python under TCG decodes slower than the bus runs: a large socket buffer lets the monitor
# work through the backlog instead of losing frames (the check is what it decodes, not its speed).
sysctl -qw net.core.rmem_default=33554432 net.core.rmem_max=33554432
"$HIL_PY" -m hapfluid.can_monitor --interface socketcan --channel vcan0 --node 3 --json --stats \
    --count 2500 >monitor.jsonl 2>monitor.err &
mon=$!
wait_for 60 can_listening vcan0 || { cat monitor.err; fail "can_monitor never bound to vcan0"; }
step "can_monitor listening"
"$HIL_BIN/haptic-device-probe" --transport socketcan --address vcan0 --node 3 --duration 2 --enable \
    --force 1.0,0.5,-0.25 --out probe.json >probe.out 2>&1 &
probe=$!
start_fake fake --transport socketcan --address vcan0 --framing can --node 3 --motion spin \
    --watchdog-ms "$HIL_WATCHDOG_MS"
wait "$probe" || { cat probe.out; fail "haptic-device-probe failed"; }
stop_pid "$FAKE_PID" "haptic-fake-device (socketcan)"
step "exchange done; waiting for can_monitor to work through 2500 frames"
wait "$mon" || { cat monitor.err; fail "can_monitor exited with an error"; }
step "can_monitor done"
cat probe.out fake.out
head -n 3 monitor.jsonl
"$HIL_PY" "$HIL_GUEST/check_can_monitor.py" monitor.jsonl probe.json 3 1.0 0.5 -0.25
