# hil-timeout: 120
# The project's fake arm on SocketCAN (classic CAN, vcan0, node 1) against the host driver
# (open_device through hil-device-check): states, commands applied, the device watchdog; the live
# traffic recorded by candump is decoded with cantools and the project's DBC, which must give
# back the exact force the host commanded: the DBC is what a rig engineer debugs the bus with.
set -eu
. "$HIL_GUEST/lib.sh"
vcan_up vcan0 16
candump -L vcan0 >candump.log &
dump=$!
wait_for 20 can_listening vcan0 || fail "candump never bound to vcan0"
start_fake fake --transport socketcan --address vcan0 --framing can --node 1 --motion stir \
    --watchdog-ms "$HIL_WATCHDOG_MS" --log fake.csv
device_check --transport socketcan --address vcan0 --node 1 \
    --force-n 1.5 --expect watchdog || { cat fake.out; fail "host driver checks on SocketCAN"; }
stop_pid "$FAKE_PID"
stop_pid "$dump"
step "driver checks done"
cat fake.out
echo "candump: $(wc -l <candump.log) frames recorded"
"$HIL_PY" -m cantools decode --single-line "$HIL_SRC/firmware_bridge/dbc/hapfluid.dbc" <candump.log >decoded.txt \
    || fail "cantools decode failed"
step "cantools decode done"
grep -m3 STATE_POS_N1 decoded.txt || fail "no STATE_POS_N1 decoded from the live traffic"
grep -m1 STATE_ROT_N1 decoded.txt || fail "no STATE_ROT_N1 decoded"
grep -m1 DEVICE_HEARTBEAT_N1 decoded.txt || fail "no DEVICE_HEARTBEAT_N1 decoded"
grep -m1 FAULT_N1 decoded.txt || fail "the watchdog FAULT_N1 report is not in the decoded traffic"
grep -m2 "CMD_FORCE_N1" decoded.txt | tee cmd.txt
grep "CMD_FORCE_N1" decoded.txt | grep -q "force_x: 1.5 N" || fail "no CMD_FORCE_N1 decoded with force_x: 1.5 N (the commanded force)"
grep "CMD_FORCE_N1" decoded.txt | grep -q "force_z: -0.75 N" || fail "no CMD_FORCE_N1 decoded with force_z: -0.75 N"
undecoded=$(grep -vc "::" decoded.txt || true)
echo "decoded lines without a DBC message: $undecoded"
[ "$undecoded" -eq 0 ] || { grep -v "::" decoded.txt | head; fail "$undecoded frames on the bus are not in the DBC"; }
pass "fake arm <-> driver over SocketCAN; $(wc -l <candump.log) live frames all decoded by cantools with the project DBC"
