# hil-timeout: 90
# haptic-rt itself, started before its CAN interface exists, as on a rig whose services start at
# boot before the USB-CAN adapter is plugged in or systemd-networkd has brought can0 up (exit 2
# would be final: the unit does not restart on it). The loop must run with the device at a link
# fault and zero wrench, name the device once with the fix, and, once vcan1 is created and the
# fake arm talks on it, take it up through the normal path: link recovery, the engage gate, the
# stand-in sim's 1.5 N rendered and applied by the device. Then the interface is removed (the
# adapter unplugged: the kernel unbinds every socket on it) and created again: link fault, then
# the same loop and the same fake device (whose transport rebinds the same way) engage again.
# Timing under TCG means nothing: the checks are that things happen, read from the loop's trace.
# The loop and the device run at 250 Hz here: at 1 kHz each, the one emulated CPU falls behind
# (the fake arm lost 70 % of its ticks) and every step takes seconds; the code path is the same.
set -eu
. "$HIL_GUEST/lib.sh"
prefix=hapfluid-hil-late
cat >rig.toml <<TOML
# Generous link timeout and sim staleness: the emulated CPU stalls for tens of ms now and then.
name = "hil-can-late"
[rt]
period_ns = 4000000
priority = 50
policy = "ignore"
[rt.shm]
prefix = "$prefix"
[[devices]]
name = "left"
wrench_mode = "interpolate"
link_timeout_ms = 100.0
sim_stale_ms = 500.0
[devices.transport]
kind = "socketcan"
address = "vcan1"
can_node_id = 4
TOML
ip link show vcan1 >/dev/null 2>&1 && fail "vcan1 exists before the test created it"

# trace_rows N: the newest N complete rows of the loop's trace as "tick faults fz overruns"
# (the last line may be half written).
trace_rows() {
    { head -n 1 trace.csv; tail -n $(($1 + 1)) trace.csv | head -n "$1"; } 2>/dev/null |
        awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
                 { print $c["tick"], $c["d0_faults"], $c["d0_fz"], $c["overruns"] }'
}
# engaged: the newest 20 ticks render the sim's 1.5 N with no fault. at_link_fault: the newest
# 20 ticks hold the device at a link timeout (fault bit 1) with exactly zero force.
engaged() { trace_rows 20 | awk '$2 != 0 || $3 < 1.0 { bad++ } END { exit !(NR == 20 && !bad) }'; }
at_link_fault() { trace_rows 20 | awk 'int($2 / 2) % 2 != 1 || $3 != 0 { bad++ } END { exit !(NR == 20 && !bad) }'; }
rt_alive() { kill -0 "$rt" 2>/dev/null || { cat rt.out; fail "haptic-rt exited: $1"; }; }

step "starting haptic-rt"
"$HIL_BIN/haptic-sim-standin" --shm-prefix "$prefix" --rate 100 --force 0,0,1.5 >sim.out 2>&1 &
sim=$!
"$HIL_BIN/haptic-rt" --rig rig.toml --trace trace.csv --flight-dir flight >rt.out 2>&1 &
rt=$!
wait_for 30 grep -q "loop thread tid" rt.out || { cat rt.out; fail "haptic-rt never started its loop"; }
hint="device 'left' (socketcan vcan1) is not connected: no CAN interface 'vcan1' up yet: waiting for it"
[ "$(grep -c "$hint" rt.out)" -eq 1 ] || { cat rt.out; fail "haptic-rt did not name the absent interface once"; }
grep -m1 "$hint" rt.out
step "haptic-rt running without vcan1"
wait_for 20 at_link_fault || { cat rt.out; fail "the loop's trace does not show the absent device at a link fault"; }
first=$(trace_rows 1)
sleep 1
rt_alive "while vcan1 was absent"
at_link_fault || fail "the absent device left its link fault, or a force reached it"
last=$(trace_rows 1)
echo "loop while vcan1 was absent: tick ${first%% *} -> ${last%% *} ($(echo "$first $last" |
    awk '{ print $5 - $1 " ticks, " $8 - $4 " overruns" }')), every tick at a link fault with zero force"
[ $(( ${last%% *} - ${first%% *} )) -ge 100 ] || fail "the loop hardly ticked while the device was absent"

step "vcan1 created"
vcan_up vcan1 16
start_fake fake --transport socketcan --address vcan1 --framing can --node 4 --motion hold --rate-hz 250 \
    --watchdog-ms "$HIL_WATCHDOG_MS" --log fake.csv
wait_for 30 engaged || { trace_rows 5; cat rt.out; fail "the loop never took up the device that appeared"; }
rt_alive "after vcan1 appeared"
step "engaged: $(trace_rows 1)"

step "vcan1 removed"
ip link del vcan1
wait_for 20 at_link_fault || { trace_rows 5; fail "the loop did not hold the device at a link fault when vcan1 went away"; }
rt_alive "while vcan1 was gone"
step "vcan1 created again"
vcan_up vcan1 16
wait_for 30 engaged || { trace_rows 5; cat rt.out fake.out; fail "the loop never took the device up again"; }
step "engaged again: $(trace_rows 1)"

kill -TERM "$rt"
rc=0
wait "$rt" || rc=$?
cat rt.out
[ $rc -eq 0 ] || fail "haptic-rt exited with status $rc on SIGTERM"
stop_pid "$FAKE_PID" "haptic-fake-device (socketcan)"
stop_pid "$sim" "haptic-sim-standin"
cat fake.out
applied=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next } $c["applied_fz"] > 1.0 { n++ } END { print n + 0 }' fake.csv)
echo "fake device: $applied ticks with more than 1 N applied along z"
[ "$applied" -ge 50 ] || fail "the device never applied the sim's force"
pass "haptic-rt started before its CAN interface: link fault with zero wrench and the device named, taken up when vcan1 appeared and again after it was removed and recreated; the device applied the sim's 1.5 N"
