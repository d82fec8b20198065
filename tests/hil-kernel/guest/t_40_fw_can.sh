# hil-timeout: 150
# The project's fake arm on SocketCAN against the host driver (open_device through
# hil-device-check), on both bus kinds a rig may have:
# - classic CAN (vcan0, MTU 16, node 1: a state spread over four 8-byte frames): states, commands
#   applied, and the fake device's own watchdog switching the motors off when the host goes silent;
# - CAN FD (vcanfd0, MTU 72, node 2: one 48-byte frame per state) with bus-off injected exactly as
#   a controller reports it (CAN_ERR_BUSOFF error frame, silence, CAN_ERR_RESTARTED): the driver
#   must report bus-off in its health and recover when states return.
# Both buses are recorded with candump and decoded with `cantools decode` and the project's DBC,
# which must give back the exact forces commanded: the DBC is what a rig engineer debugs with.
set -eu
. "$HIL_GUEST/lib.sh"
vcan_up vcan0 16
vcan_up vcanfd0 72
candump -L vcan0 >classic.log &
dump1=$!
# 0:0 = every frame, #FFFFFFFF = and every error class (error frames need an explicit mask)
candump -L vcanfd0,0:0,#FFFFFFFF >fd.log &
dump2=$!
wait_for 20 can_listening vcan0 || fail "candump never bound to vcan0"
wait_for 20 can_listening vcanfd0 || fail "candump never bound to vcanfd0"

step "classic CAN"
start_fake classic --transport socketcan --address vcan0 --framing can --node 1 --motion stir \
    --watchdog-ms "$HIL_WATCHDOG_MS"
device_check --transport socketcan --address vcan0 --node 1 --force-n 1.5 --expect watchdog \
    || { cat classic.out; fail "host driver checks on classic CAN"; }
stop_pid "$FAKE_PID" "haptic-fake-device (socketcan)"
cat classic.out

step "CAN FD with bus-off"
start_fake fd --transport socketcan --address vcanfd0 --framing canfd --node 2 --motion spin \
    --watchdog-ms "$HIL_WATCHDOG_MS" --bus-off-at 4 --bus-off-ms 300
device_check --transport socketcan --address vcanfd0 --fd 1 --node 2 --force-n -2.0 --expect bus-off \
    || { cat fd.out; fail "host driver checks on CAN FD"; }
stop_pid "$FAKE_PID" "haptic-fake-device (socketcan FD)"
stop_pid "$dump1"
stop_pid "$dump2"
cat fd.out
grep -q "bus-off at" fd.out || fail "the fake device did not inject bus-off"
# Error frames (CAN_ERR_FLAG, 8-digit IDs 2xxxxxxx) are the controller's, not the protocol's.
errors=$(grep -cE " vcanfd0 2[0-9A-F]{7}#" fd.log || true)
echo "error frames on vcanfd0: $errors"
[ "$errors" -ge 1 ] || fail "candump saw no error frame although the fake device reported bus-off"

step "cantools decode"
echo "candump: $(wc -l <classic.log) classic and $(wc -l <fd.log) FD frames recorded"
cat classic.log fd.log >all.log
candump_sample all.log >sample.log
echo "decoding $(wc -l <sample.log) frames: the first and last 10 of each of" \
    "$(awk '{split($3,a,"#"); print a[1]}' all.log | sort -u | wc -l) CAN IDs"
cantools_decode "$HIL_SRC/firmware_bridge/dbc/hapfluid.dbc" <sample.log >decoded.txt \
    || fail "cantools decode failed"
step "decoded"
for m in STATE_POS_N1 STATE_ROT_N1 STATE_VEL_N1 STATE_ANGVEL_N1 DEVICE_HEARTBEAT_N1 FAULT_N1 FD_STATE_N2; do
    grep -m1 " $m(" decoded.txt | cut -c1-220 || fail "no $m decoded from the live traffic"
done
grep " CMD_FORCE_N1(" decoded.txt | grep -m1 "force_x: 1.5 N, force_y: 0.0 N, force_z: -0.75 N, enable: 1" \
    || fail "no CMD_FORCE_N1 decoded with the commanded 1.5 / 0 / -0.75 N, enable"
grep " FD_COMMAND_N2(" decoded.txt | grep -m1 "force_x: -2.0 N, force_y: 0.0 N, force_z: 1.0 N" | cut -c1-220 \
    || fail "no FD_COMMAND_N2 decoded with the commanded -2 / 0 / 1 N"
undecoded=$(grep -v "::" decoded.txt | grep -vcE " 2[0-9A-F]{7}#" || true)
echo "frames without a DBC message: $undecoded"
[ "$undecoded" -eq 0 ] || { grep -v "::" decoded.txt | head; fail "$undecoded frames on the bus are not in the DBC"; }
pass "fake arm <-> driver on classic CAN (watchdog) and CAN FD (bus-off); every CAN ID decoded by cantools with the project DBC"
