# hil-timeout: 120
# The project's fake arm on CAN FD (vcanfd0, MTU 72, node 2: one 48-byte FD frame per state)
# against the host driver, with bus-off injected by the fake device exactly as a CAN controller
# reports it (CAN_ERR_BUSOFF error frame, silence, CAN_ERR_RESTARTED): the driver must report
# bus-off in its health and recover when states return. candump + cantools decode the FD traffic.
set -eu
. "$HIL_GUEST/lib.sh"
vcan_up vcanfd0 72
candump -L vcanfd0 >candump.log &
dump=$!
wait_for 20 can_listening vcanfd0 || fail "candump never bound to vcanfd0"
start_fake fake --transport socketcan --address vcanfd0 --framing canfd --node 2 --motion spin \
    --watchdog-ms "$HIL_WATCHDOG_MS" --bus-off-at 3 --bus-off-ms 300
step "fake device up"
device_check --transport socketcan --address vcanfd0 --fd 1 --node 2 \
    --force-n -2.0 --expect bus-off || { cat fake.out; fail "host driver checks on CAN FD"; }
stop_pid "$FAKE_PID"
stop_pid "$dump"
step "driver checks done"
cat fake.out
grep -q "bus-off at" fake.out || fail "the fake device did not inject bus-off"
echo "candump: $(wc -l <candump.log) frames recorded"
"$HIL_PY" -m cantools decode --single-line "$HIL_SRC/firmware_bridge/dbc/hapfluid.dbc" <candump.log >decoded.txt \
    || fail "cantools decode failed"
step "cantools decode done"
grep -m2 FD_STATE_N2 decoded.txt || fail "no FD_STATE_N2 decoded from the live traffic"
grep FD_COMMAND_N2 decoded.txt | grep -m1 "force_x: -2.0 N" || fail "no FD_COMMAND_N2 with force_x: -2.0 N decoded"
undecoded=$(grep -v "::" decoded.txt | grep -vc "#" || true)
grep -v "::" decoded.txt | head -5
pass "fake arm <-> driver over CAN FD with bus-off reported and recovered; $(wc -l <candump.log) FD frames decoded"
